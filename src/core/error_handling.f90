!> The one stop path of Agglo for errors: print the message once, write it to the log, exit non-zero.
!>  - An error every rank detects together (the deck checks: every rank parses the same text):
!>    rank 0 prints the message, every rank finalizes MPI and exits with status 2. No MPI_Abort,
!>    so the message is the last line the program prints (mpirun adds its own note on the
!>    non-zero status unless started with `mpirun -q`). A check only some ranks make (rank 0 looks at
!>    a directory, each rank looks for a file) shares its answer first (parallel_env: all_ranks,
!>    any_rank, root_text) so that a user's error still ends this way.
!>  - An error only one rank detects: that rank prints it with its rank number and calls
!>    MPI_Abort, which stops every rank (Open MPI then prints its abort banner).
module error_handling
  use, intrinsic :: iso_c_binding, only: c_int
  use mpi_f08, only: MPI_Abort, MPI_Finalize, MPI_Comm_rank, MPI_COMM_WORLD, MPI_Initialized, MPI_Finalized
  use logger, only: log_error_line, log_is_root, log_close
  implicit none
  private
  public :: fatal, input_error, input_error_text

  integer, parameter :: abort_code = 2

  interface
    !> C's exit(): ends the process with a status and no text (Fortran's STOP and ERROR STOP print
    !> their code on standard error, which would follow the message).
    subroutine c_exit(status) bind(c, name='exit')
      import :: c_int
      integer(c_int), value :: status
    end subroutine c_exit
  end interface

contains

  !> Stop the run with a message.
  !> collective = .true. (default): every rank detected the same error at the same point of the
  !> program (a caller that is not sure must pass .false.: a lone rank in MPI_Finalize would wait).
  !> collective = .false.: only this rank knows; it prints the message with its rank and aborts.
  subroutine fatal(message, collective)
    character(len=*), intent(in) :: message
    logical, intent(in), optional :: collective
    logical :: all_ranks, mpi_up, mpi_down
    integer :: rank
    character(len=16) :: rank_text
    all_ranks = .true.
    if (present(collective)) all_ranks = collective
    call MPI_Initialized(mpi_up)
    call MPI_Finalized(mpi_down)
    if (all_ranks) then
      if (log_is_root()) call log_error_line('agglo: error: '//trim(message))
      call log_close()
      if (mpi_up .and. .not. mpi_down) call MPI_Finalize()
      call c_exit(int(abort_code, c_int))
    end if
    rank = 0
    if (mpi_up .and. .not. mpi_down) call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    write(rank_text, '(i0)') rank
    call log_error_line('agglo: error (rank '//trim(rank_text)//'): '//trim(message))
    if (mpi_up .and. .not. mpi_down) call MPI_Abort(MPI_COMM_WORLD, abort_code)
    call c_exit(int(abort_code, c_int))
  end subroutine fatal

  !> A deck error naming the namelist group, the variable, the bad value and the allowed range.
  subroutine input_error(group, variable, value, allowed)
    character(len=*), intent(in) :: group, variable, value, allowed
    call fatal(input_error_text(group, variable, value, allowed))
  end subroutine input_error

  !> The message of input_error, for a check that only some ranks make (the caller shares it first).
  function input_error_text(group, variable, value, allowed) result(message)
    character(len=*), intent(in) :: group, variable, value, allowed
    character(len=:), allocatable :: message
    message = 'deck: &'//trim(group)//' '//trim(variable)//' = '//trim(value)//' is not allowed; allowed: '//trim(allowed)
  end function input_error_text
end module error_handling
