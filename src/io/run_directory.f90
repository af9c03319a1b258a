!> The run directory: created if needed, checked writable, never silently reused.
!> A directory that already holds a run (its run.nml) is refused unless the deck says
!> &run restart = .true. (continue it) or &run overwrite = .true. (replace it).
module run_directory
  use agglo_config, only: agglo_config_t, write_config
  use error_handling, only: fatal, input_error
  use parallel_env, only: is_root, barrier
  use file_system, only: rename_file, file_exists, make_directory, delete_file
  use directory_listing, only: list_directory, name_length
  implicit none
  private
  public :: prepare_run_directory, run_directory_path, run_file

  character(len=:), allocatable :: directory

contains

  !> The directory of this run ('' until prepare_run_directory is called).
  function run_directory_path() result(path)
    character(len=:), allocatable :: path
    path = ''
    if (allocated(directory)) path = directory
  end function run_directory_path

  !> Path of a file inside the run directory.
  function run_file(name) result(path)
    character(len=*), intent(in) :: name
    character(len=:), allocatable :: path
    path = run_directory_path()//'/'//trim(name)
  end function run_file

  subroutine prepare_run_directory(cfg)
    type(agglo_config_t), intent(in) :: cfg
    logical :: has_run, ok
    integer :: unit, ios
    directory = trim(cfg%output%directory)
    if (len(directory) == 0) directory = 'output/'//trim(cfg%run%name)
    if (is_root()) then
      has_run = file_exists(directory//'/run.nml')
      if (cfg%run%restart) then
        if (.not. has_run) call input_error('run', 'restart', '.true.', &
            '.false. (no earlier run found in '//directory//' to continue)')
      else if (has_run .and. .not. cfg%run%overwrite) then
        call input_error('output', 'directory', ''''//directory//'''', &
            'a directory without an earlier run in it, or set &run overwrite = .true. to replace that run')
      end if
      call make_directory(directory, ok)
      if (.not. ok) call input_error('output', 'directory', ''''//directory//'''', &
          'a directory that can be created (mkdir failed)')
      open(newunit=unit, file=directory//'/.agglo_write_probe', status='replace', action='write', iostat=ios)
      if (ios /= 0) call input_error('output', 'directory', ''''//directory//'''', 'a writable directory')
      close(unit, status='delete')
      if (cfg%run%overwrite .and. has_run .and. .not. cfg%run%restart) call remove_earlier_run()
      call write_run_deck(cfg)
    end if
    call barrier()
  end subroutine prepare_run_directory

  !> Replace an earlier run: delete the files Agglo writes (and nothing else), so that its
  !> checkpoints are not picked up by a later restart and its snapshots do not end up in the new
  !> fields.xdmf.
  subroutine remove_earlier_run()
    character(len=name_length), allocatable :: names(:)
    logical :: ok
    integer :: i, status
    call execute_command_line('rm -rf "'//directory//'/checkpoints"', exitstat=status)
    call list_directory(directory, names, ok)
    do i = 1, size(names)
      if (is_run_output(names(i))) call delete_file(directory//'/'//trim(names(i)))
    end do
  end subroutine remove_earlier_run

  !> The file names Agglo writes into a run directory (docs/outputs.md).
  logical function is_run_output(name)
    character(len=*), intent(in) :: name
    character(len=*), parameter :: fixed(*) = [character(len=24) :: 'agglo.log', 'fields.xdmf', &
        'fluid_statistics.dat', 'particles.h5', 'summary.json', 'flow_statistics.h5', 'run.nml']
    is_run_output = any(fixed == name) .or. (index(name, 'fields_') == 1 .and. index(name, '.h5') > 0)
  end function is_run_output

  !> run.nml: the fully resolved deck, written to a temporary name and renamed when complete.
  subroutine write_run_deck(cfg)
    type(agglo_config_t), intent(in) :: cfg
    integer :: unit
    logical :: ok
    open(newunit=unit, file=directory//'/run.nml.tmp', status='replace', action='write')
    write(unit, '(a)') '! Resolved deck of this run (every variable, defaults included).'
    write(unit, '(a)') '! Deck file: '//trim(cfg%deck_path)
    call write_config(unit, cfg)
    close(unit)
    call rename_file(directory//'/run.nml.tmp', directory//'/run.nml', ok)
    if (.not. ok) call fatal('cannot rename '//directory//'/run.nml.tmp', collective=.false.)
  end subroutine write_run_deck
end module run_directory
