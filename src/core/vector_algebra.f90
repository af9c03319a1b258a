!> Small 3-D vector algebra used by the particle code (one definition for every module).
module vector_algebra
  use agglo_kinds, only: wp
  implicit none
  private
  public :: cross, skew, outer

contains

  !> a x b.
  pure function cross(a, b) result(c)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: c(3)
    c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
  end function cross

  !> [a]x, the matrix with [a]x b = a x b.
  pure function skew(a) result(s)
    real(wp), intent(in) :: a(3)
    real(wp) :: s(3, 3)
    s = reshape([0.0_wp, a(3), -a(2), -a(3), 0.0_wp, a(1), a(2), -a(1), 0.0_wp], [3, 3])
  end function skew

  !> u v^T.
  pure function outer(u, v) result(m)
    real(wp), intent(in) :: u(3), v(3)
    real(wp) :: m(3, 3)
    integer :: j
    do j = 1, 3
      m(:, j) = u * v(j)
    end do
  end function outer
end module vector_algebra
