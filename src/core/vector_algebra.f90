!> Small 3-D vector algebra used by the particle code (one definition for every module).
module vector_algebra
  use agglo_kinds, only: wp
  implicit none
  private
  public :: cross, skew, outer, symmetric_eigenvalues3

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

  !> Eigenvalues of a symmetric 3x3 matrix, ascending, by cyclic Jacobi rotations (Golub & Van Loan,
  !> Matrix Computations, section 8.5): each rotation zeroes one off-diagonal entry with the stable
  !> tangent t = sign(theta) / (|theta| + sqrt(theta^2 + 1)); the sweeps converge quadratically and
  !> give every eigenvalue to round-off of the matrix norm, including equal ones (where the closed
  !> trigonometric formula loses half the digits).
  pure function symmetric_eigenvalues3(matrix) result(lambda)
    real(wp), intent(in) :: matrix(3, 3)
    real(wp) :: lambda(3)
    real(wp) :: a(3, 3), theta, t, c, s, off, scale, held, apk, aqk
    integer :: sweep, p, q, k, i, j
    integer, parameter :: pairs(2, 3) = reshape([1, 2, 1, 3, 2, 3], [2, 3])
    a = 0.5_wp * (matrix + transpose(matrix))
    scale = sqrt(sum(a**2))
    do sweep = 1, 50
      off = a(1, 2)**2 + a(1, 3)**2 + a(2, 3)**2
      if (off <= (epsilon(1.0_wp) * scale)**2 * 1.0e-4_wp) exit
      do k = 1, 3
        p = pairs(1, k)
        q = pairs(2, k)
        if (a(p, q) == 0.0_wp) cycle
        theta = (a(q, q) - a(p, p)) / (2.0_wp * a(p, q))
        t = sign(1.0_wp, theta) / (abs(theta) + sqrt(theta**2 + 1.0_wp))
        c = 1.0_wp / sqrt(t**2 + 1.0_wp)
        s = t * c
        ! A <- J^T A J with J the rotation in the (p, q) plane; a(p, q) becomes 0.
        do i = 1, 3
          apk = a(i, p)
          aqk = a(i, q)
          a(i, p) = c * apk - s * aqk
          a(i, q) = s * apk + c * aqk
        end do
        do j = 1, 3
          apk = a(p, j)
          aqk = a(q, j)
          a(p, j) = c * apk - s * aqk
          a(q, j) = s * apk + c * aqk
        end do
        a(p, q) = 0.0_wp
        a(q, p) = 0.0_wp
      end do
    end do
    lambda = [a(1, 1), a(2, 2), a(3, 3)]
    do i = 2, 3
      held = lambda(i)
      j = i - 1
      do while (j >= 1)
        if (lambda(j) <= held) exit
        lambda(j + 1) = lambda(j)
        j = j - 1
      end do
      lambda(j + 1) = held
    end do
  end function symmetric_eigenvalues3
end module vector_algebra
