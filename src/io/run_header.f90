!> The head of every run log: what was built how, on what, with which deck.
module run_header
  use, intrinsic :: iso_fortran_env, only: compiler_version, compiler_options
  use mpi_f08, only: MPI_Get_library_version, MPI_MAX_LIBRARY_VERSION_STRING
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  use parallel_env, only: n_ranks, is_root
  use run_directory, only: run_directory_path, run_file
  implicit none
  private
  public :: log_run_header

contains

  subroutine log_run_header(cfg)
    type(agglo_config_t), intent(in) :: cfg
    character(len=MPI_MAX_LIBRARY_VERSION_STRING) :: mpi_version
    character(len=32) :: ranks_text
    character(len=512) :: line
    integer :: length, unit, ios
    call MPI_Get_library_version(mpi_version, length)
    write(ranks_text, '(i0)') n_ranks
    call log_line('Agglo: particle-resolved DNS of attractive spheroid pairs')
    call log_line('  compiler: '//compiler_version())
    call log_line('  options:  '//compiler_options())
    call log_line('  MPI:      '//trim(first_line(mpi_version(1:length))))
    call log_line('  ranks:    '//trim(ranks_text))
    call log_line('  deck:     '//trim(cfg%deck_path))
    call log_line('  output:   '//run_directory_path())
    call log_line('  run:      '//trim(cfg%run%name)//merge(' (restart)', '          ', cfg%run%restart))
    call log_line('Resolved deck (run.nml):')
    if (is_root()) then
      open(newunit=unit, file=run_file('run.nml'), status='old', action='read', iostat=ios)
      do while (ios == 0)
        read(unit, '(a)', iostat=ios) line
        if (ios == 0) call log_line('  '//trim(line))
      end do
      close(unit)
    end if
  end subroutine log_run_header

  function first_line(text) result(line)
    character(len=*), intent(in) :: text
    character(len=len(text)) :: line
    integer :: cut
    cut = index(text, new_line('a'))
    line = text
    if (cut > 0) line = text(1:cut - 1)
  end function first_line
end module run_header
