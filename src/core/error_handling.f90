!> The one abort path of Agglo: print the message, write it to the log, MPI_Abort non-zero.
module error_handling
  use mpi_f08, only: MPI_Abort, MPI_COMM_WORLD, MPI_Initialized, MPI_Finalized
  use logger, only: log_error_line, log_is_root
  implicit none
  private
  public :: fatal, input_error

  integer, parameter :: abort_code = 2

contains

  !> Stop the run with a message.
  !> collective = .true. (default): every rank detected the same error; rank 0 prints it and
  !> aborts, the other ranks wait a moment so the message is not lost when they are killed.
  !> collective = .false.: only this rank knows; it prints and aborts at once.
  subroutine fatal(message, collective)
    character(len=*), intent(in) :: message
    logical, intent(in), optional :: collective
    logical :: all_ranks, mpi_up, mpi_down
    all_ranks = .true.
    if (present(collective)) all_ranks = collective
    call MPI_Initialized(mpi_up)
    call MPI_Finalized(mpi_down)
    if (log_is_root() .or. .not. all_ranks) call log_error_line('agglo: error: '//trim(message))
    if (.not. mpi_up .or. mpi_down) error stop abort_code
    if (all_ranks .and. .not. log_is_root()) call sleep(3)
    call MPI_Abort(MPI_COMM_WORLD, abort_code)
    error stop abort_code
  end subroutine fatal

  !> A deck error naming the namelist group, the variable, the bad value and the allowed range.
  subroutine input_error(group, variable, value, allowed)
    character(len=*), intent(in) :: group, variable, value, allowed
    call fatal('deck: &'//trim(group)//' '//trim(variable)//' = '//trim(value)// &
               ' is not allowed; allowed: '//trim(allowed))
  end subroutine input_error
end module error_handling
