!> Order statistics of small samples (benchmark repetitions, timings).
module sample_statistics
  use agglo_kinds, only: wp
  implicit none
  private
  public :: median, sorted_values

contains

  !> The median (for an even count the lower of the two middle values).
  real(wp) function median(values)
    real(wp), intent(in) :: values(:)
    real(wp) :: sorted(size(values))
    sorted = sorted_values(values)
    median = sorted((size(sorted) + 1) / 2)
  end function median

  !> A copy of values in ascending order, by insertion sort: the samples are a few dozen
  !> repetitions at most.
  pure function sorted_values(values) result(sorted)
    real(wp), intent(in) :: values(:)
    real(wp) :: sorted(size(values)), held
    integer :: i, j
    sorted = values
    do i = 2, size(sorted)
      held = sorted(i); j = i - 1
      do while (j >= 1)
        if (sorted(j) <= held) exit
        sorted(j + 1) = sorted(j); j = j - 1
      end do
      sorted(j + 1) = held
    end do
  end function sorted_values
end module sample_statistics
