!> Agglo main program: read the deck -> prepare the run -> the scene loop runs what it switches on.
!> Command line: agglo DECK.nml [--set group.variable=value]... [--print-deck]
!>   --set          overrides a deck variable (value as written in a deck); checked like the deck
!>   --print-deck   checks the deck with the overrides and prints its text with the overrides
!>                  merged (a deck of its own), then stops without running anything
program agglo
  use, intrinsic :: iso_fortran_env, only: output_unit
  use agglo_config, only: agglo_config_t
  use config_reader, only: read_config
  use deck_file, only: deck_t, int_text
  use error_handling, only: fatal
  use logger, only: log_open, log_line, log_close, log_is_root
  use parallel_env, only: parallel_start, parallel_stop, n_ranks
  use run_directory, only: prepare_run_directory, run_file
  use run_header, only: log_run_header
  use hdf5_files, only: h5_finalize
  use scene_loop, only: run_scene
  implicit none
  character(len=*), parameter :: usage = 'usage: agglo DECK.nml [--set group.variable=value]... [--print-deck]'// &
      '   (run with mpirun -np N for N ranks; docs/decks.md)'
  type(agglo_config_t) :: cfg
  type(deck_t) :: deck
  character(len=:), allocatable :: deck_path, argument
  character(len=:), allocatable :: overrides(:)
  logical :: print_deck
  integer :: i

  call parallel_start()
  call read_arguments()
  call read_config(deck_path, n_ranks, cfg, overrides, deck)
  if (print_deck) then
    if (log_is_root()) then
      do i = 1, size(deck%lines)
        write(output_unit, '(a)') trim(deck%lines(i))
      end do
    end if
    call parallel_stop()
    stop
  end if
  call prepare_run_directory(cfg)
  call log_open(run_file('agglo.log'))
  call log_run_header(cfg)

  call run_scene(cfg)   ! the one time loop of every scene (driver/scene_loop)

  call log_line('agglo: run complete; outputs in '//run_file(''))
  call log_close()
  call h5_finalize()
  call parallel_stop()

contains

  !> The deck path, the --set overrides in order, and --print-deck.
  subroutine read_arguments()
    integer :: k, n_set
    deck_path = ''
    print_deck = .false.
    n_set = 0
    allocate(character(len=1) :: overrides(0))
    k = 1
    do while (k <= command_argument_count())
      argument = argument_text(k)
      if (argument == '--set') then
        if (k == command_argument_count()) call fatal('--set needs group.variable=value after it; '//usage)
        k = k + 1
        call add_override(argument_text(k))
      else if (argument(1:min(6, len(argument))) == '--set=') then
        call add_override(argument(7:))
      else if (argument == '--print-deck') then
        print_deck = .true.
      else if (argument == '-h' .or. argument == '--help') then
        call fatal(usage)
      else if (len(deck_path) == 0 .and. argument(1:min(1, len(argument))) /= '-') then
        deck_path = argument
      else
        call fatal('unknown argument "'//argument//'"; '//usage)
      end if
      k = k + 1
    end do
    if (len(deck_path) == 0) call fatal(usage)
    if (len(deck_path) > len(cfg%deck_path)) call fatal('the deck path is longer than '// &
        'the '//int_text(len(cfg%deck_path))//' characters allowed: '//deck_path(1:80)//'...')
  end subroutine read_arguments

  subroutine add_override(text)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: grown(:)
    allocate(character(len=max(len(overrides), len(text))) :: grown(size(overrides) + 1))
    grown(1:size(overrides)) = overrides
    grown(size(grown)) = text
    call move_alloc(grown, overrides)
  end subroutine add_override

  function argument_text(k) result(text)
    integer, intent(in) :: k
    character(len=:), allocatable :: text
    integer :: length
    call get_command_argument(k, length=length)
    allocate(character(len=length) :: text)
    if (length > 0) call get_command_argument(k, text)
  end function argument_text
end program agglo
