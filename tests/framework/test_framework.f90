!> Agglo's unit-test support in the pFUnit style: named checks with stated tolerances.
!> Every check prints one line "PASS name" or "FAIL name: detail" (rank 0 only); test_finish
!> prints "N passed, N failed" for the program and exits non-zero if anything failed.
!> tests/run_tests.sh adds the lines of all programs into the suite's closing line.
module test_framework
  use, intrinsic :: iso_fortran_env, only: output_unit
  use mpi_f08, only: MPI_Initialized, MPI_Finalized, MPI_Comm_rank, MPI_COMM_WORLD, MPI_Finalize, &
                     MPI_Allreduce, MPI_IN_PLACE, MPI_INTEGER, MPI_MAX, MPI_MIN
  use agglo_kinds, only: wp
  implicit none
  private
  public :: test_start, test_finish, check, check_close, check_below, check_above, check_equal, on_every_rank

  integer :: passed = 0, failed = 0
  character(len=64) :: suite = ''

contains

  subroutine test_start(suite_name)
    character(len=*), intent(in) :: suite_name
    suite = suite_name
    passed = 0
    failed = 0
  end subroutine test_start

  !> ok holds on every rank (the same answer on each; collective): for a check each rank makes
  !> of its own data, counted by a reduction of the test's own, not by the code under test.
  logical function on_every_rank(ok)
    logical, intent(in) :: ok
    integer :: value
    value = merge(1, 0, ok)
    call MPI_Allreduce(MPI_IN_PLACE, value, 1, MPI_INTEGER, MPI_MIN, MPI_COMM_WORLD)
    on_every_rank = (value == 1)
  end function on_every_rank

  logical function on_root()
    logical :: up, down
    integer :: rank
    call MPI_Initialized(up)
    call MPI_Finalized(down)
    rank = 0
    if (up .and. .not. down) call MPI_Comm_rank(MPI_COMM_WORLD, rank)
    on_root = (rank == 0)
  end function on_root

  subroutine report(ok, name, detail)
    logical, intent(in) :: ok
    character(len=*), intent(in) :: name, detail
    if (ok) then
      passed = passed + 1
      if (on_root()) write(output_unit, '(a)') 'PASS '//trim(suite)//'/'//trim(name)//'  '//trim(detail)
    else
      failed = failed + 1
      if (on_root()) write(output_unit, '(a)') 'FAIL '//trim(suite)//'/'//trim(name)//': '//trim(detail)
    end if
    flush(output_unit)
  end subroutine report

  subroutine check(condition, name, detail)
    logical, intent(in) :: condition
    character(len=*), intent(in) :: name
    character(len=*), intent(in), optional :: detail
    if (present(detail)) then
      call report(condition, name, detail)
    else
      call report(condition, name, '')
    end if
  end subroutine check

  !> |actual - expected| <= rel_tol |expected| + abs_tol (abs_tol defaults to 0). NaN fails.
  subroutine check_close(actual, expected, rel_tol, name, abs_tol)
    real(wp), intent(in) :: actual, expected, rel_tol
    character(len=*), intent(in) :: name
    real(wp), intent(in), optional :: abs_tol
    real(wp) :: bound
    character(len=160) :: detail
    bound = rel_tol * abs(expected)
    if (present(abs_tol)) bound = bound + abs_tol
    write(detail, '(a,es14.7,a,es14.7,a,es9.2)') 'actual ', actual, ' expected ', expected, ' tol ', bound
    call report(abs(actual - expected) <= bound, name, detail)
  end subroutine check_close

  !> value <= bound (NaN fails).
  subroutine check_below(value, bound, name)
    real(wp), intent(in) :: value, bound
    character(len=*), intent(in) :: name
    character(len=96) :: detail
    write(detail, '(a,es12.5,a,es12.5)') 'value ', value, ' <= ', bound
    call report(value <= bound, name, detail)
  end subroutine check_below

  !> value >= bound (NaN fails).
  subroutine check_above(value, bound, name)
    real(wp), intent(in) :: value, bound
    character(len=*), intent(in) :: name
    character(len=96) :: detail
    write(detail, '(a,es12.5,a,es12.5)') 'value ', value, ' >= ', bound
    call report(value >= bound, name, detail)
  end subroutine check_above

  subroutine check_equal(actual, expected, name)
    integer, intent(in) :: actual, expected
    character(len=*), intent(in) :: name
    character(len=64) :: detail
    write(detail, '(a,i0,a,i0)') 'actual ', actual, ' expected ', expected
    call report(actual == expected, name, detail)
  end subroutine check_equal

  !> Print this program's tally, finalize MPI if it is running, exit 1 on any failure.
  subroutine test_finish()
    logical :: up, down, root
    integer :: any_failed
    root = on_root()
    call MPI_Initialized(up)
    call MPI_Finalized(down)
    any_failed = merge(1, 0, failed > 0)
    if (up .and. .not. down) then
      call MPI_Allreduce(MPI_IN_PLACE, any_failed, 1, MPI_INTEGER, MPI_MAX, MPI_COMM_WORLD)
      call MPI_Finalize()
    end if
    if (root) write(output_unit, '(i0,a,i0,a)') passed, ' passed, ', failed, ' failed'
    if (any_failed > 0) error stop 1
  end subroutine test_finish
end module test_framework
