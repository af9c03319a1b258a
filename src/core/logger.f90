!> Run log: every line goes to standard output and to the log file, from rank 0 only.
!> The rank is set once by the parallel layer (log_set_rank) so this module needs no MPI.
module logger
  use, intrinsic :: iso_fortran_env, only: output_unit, error_unit
  implicit none
  private
  public :: log_open, log_close, log_line, log_error_line, log_set_rank, log_is_root

  integer :: log_unit = -1
  integer :: my_rank = 0

contains

  subroutine log_set_rank(rank)
    integer, intent(in) :: rank
    my_rank = rank
  end subroutine log_set_rank

  logical function log_is_root()
    log_is_root = (my_rank == 0)
  end function log_is_root

  !> Open (append to) the log file on rank 0.
  subroutine log_open(path)
    character(len=*), intent(in) :: path
    integer :: ios
    if (my_rank /= 0) return
    if (log_unit /= -1) close(log_unit)
    open(newunit=log_unit, file=path, status='unknown', position='append', action='write', iostat=ios)
    if (ios /= 0) then
      log_unit = -1
      write(error_unit, '(a)') 'agglo: warning: cannot open log file '//trim(path)
    end if
  end subroutine log_open

  subroutine log_close()
    if (log_unit /= -1) close(log_unit)
    log_unit = -1
  end subroutine log_close

  !> One line to standard output and the log (rank 0 only).
  subroutine log_line(text)
    character(len=*), intent(in) :: text
    if (my_rank /= 0) return
    write(output_unit, '(a)') text
    flush(output_unit)
    if (log_unit /= -1) then
      write(log_unit, '(a)') text
      flush(log_unit)
    end if
  end subroutine log_line

  !> An error line to standard error and the log, from whichever rank calls it.
  subroutine log_error_line(text)
    character(len=*), intent(in) :: text
    write(error_unit, '(a)') text
    flush(error_unit)
    if (log_unit /= -1) then
      write(log_unit, '(a)') text
      flush(log_unit)
    end if
  end subroutine log_error_line
end module logger
