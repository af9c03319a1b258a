!> The semi-axes of a spheroid as the decks give it (&pair, &bodies, &suspension): shape, the
!> volume-equivalent radius r and the aspect ratio (needle a/b, disk b/a, both >= 1; 'spheroid' a/b),
!> with a b^2 = r^3 (the convention of particles/spheroid.f90), for the checks made before a run.
module config_shapes
  use agglo_kinds, only: wp
  implicit none
  private
  public :: deck_semi_axes

contains

  !> [a, b]: the semi-axis along the symmetry axis and the two equal ones (m).
  pure function deck_semi_axes(shape, radius, aspect_ratio) result(axes)
    character(len=*), intent(in) :: shape
    real(wp), intent(in) :: radius, aspect_ratio
    real(wp) :: axes(2), ratio
    ratio = 1.0_wp
    select case (trim(shape))
    case ('needle', 'spheroid')
      ratio = aspect_ratio
    case ('disk')
      ratio = 1.0_wp / aspect_ratio
    end select
    axes(2) = radius * ratio**(-1.0_wp / 3.0_wp)
    axes(1) = ratio * axes(2)
  end function deck_semi_axes

end module config_shapes
