!> Minimum-image arithmetic in a periodic box, shared by the particle system (pair separations)
!> and the immersed boundary (node-to-body offsets). A period of 0 (or less) means an unbounded
!> direction: the separation is returned unchanged.
module periodic_box
  use agglo_kinds, only: wp
  implicit none
  private
  public :: minimum_image, image_shift, image_periods

contains

  !> The whole number of periods to add to a separation to get its minimum image (0 where unbounded).
  elemental function image_shift(separation, period) result(shift)
    real(wp), intent(in) :: separation, period
    real(wp) :: shift
    shift = 0.0_wp
    if (period > 0.0_wp) shift = -period * anint(separation / period)
  end function image_shift

  !> The image of a separation in (-period/2, period/2] (ties go away from zero, as anint does).
  elemental function minimum_image(separation, period) result(image)
    real(wp), intent(in) :: separation, period
    real(wp) :: image
    ! Within half a period (most calls) anint gives +-0, so the shift is a zero: the sum below is the
    ! general formula's value, bit for bit (signed zeros included), without the rounding call.
    if (period > 0.0_wp) then
      if (abs(separation / period) < 0.5_wp) then
        image = separation + 0.0_wp
        return
      end if
    end if
    image = separation + image_shift(separation, period)
  end function minimum_image

  !> image_shift in whole periods: the lattice vector n with separation + n L the minimum image
  !> (0 where unbounded). Integer, so that sums of image shifts around a cycle are exact.
  elemental function image_periods(separation, period) result(periods)
    real(wp), intent(in) :: separation, period
    integer :: periods
    periods = 0
    if (period > 0.0_wp) periods = -nint(separation / period)
  end function image_periods

end module periodic_box
