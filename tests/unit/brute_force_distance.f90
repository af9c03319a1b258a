!> Independent brute-force reference for the closest-points tests: exact point-to-spheroid distance
!> (Eberly 2013) and the gap of two spheroids by dense sampling of body 1's surface refined locally.
!> Deliberately unrelated to the method of src/particles/closest_points.f90 (support functions).
module brute_force_distance
  use agglo_kinds, only: wp
  use vector_algebra, only: cross
  use physical_constants, only: pi
  use spheroid, only: spheroid_t
  implicit none
  private
  public :: point_ellipse_distance, point_body_distance, brute_force_gap

  ! The pair being sampled (set by brute_force_gap; the refinement routines read it).
  type(spheroid_t) :: b1, b2
  real(wp) :: x1(3), x2(3), r1(3,3), r2(3,3)

contains

  !> Distance of the point (u, w) (u, w >= 0, outside) from the ellipse u^2/a^2 + w^2/b^2 = 1.
  !> Eberly (2013), "Distance from a point to an ellipse, an ellipsoid, or a hyperellipsoid": the closest
  !> point is (a^2 u/(t + a^2), b^2 w/(t + b^2)) with t > 0 the root of
  !> F(t) = (a u/(t + a^2))^2 + (b w/(t + b^2))^2 - 1, decreasing, with F(sqrt(a^2 u^2 + b^2 w^2)) <= 0;
  !> bisection to the last bit.
  function point_ellipse_distance(a, b, u, w) result(distance)
    real(wp), intent(in) :: a, b, u, w
    real(wp) :: distance, lo, hi, mid, f
    integer :: it
    lo = 0.0_wp
    hi = sqrt((a * u)**2 + (b * w)**2)
    do it = 1, 300
      mid = 0.5_wp * (lo + hi)
      if (mid <= lo .or. mid >= hi) exit
      f = (a * u / (mid + a**2))**2 + (b * w / (mid + b**2))**2 - 1.0_wp
      if (f > 0.0_wp) then
        lo = mid
      else
        hi = mid
      end if
    end do
    distance = hypot(u - a**2 * u / (mid + a**2), w - b**2 * w / (mid + b**2))
  end function point_ellipse_distance

  !> Distance from the lab point x (outside) to body 2.
  function point_body_distance(body, centre, rot, x) result(distance)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: centre(3), rot(3,3), x(3)
    real(wp) :: distance, y(3)
    y = matmul(x - centre, rot)
    distance = point_ellipse_distance(body%a, body%b, abs(y(1)), norm2(y(2:3)))
  end function point_body_distance

  !> Brute-force gap (an upper bound of the true distance, since it is the distance of an actual
  !> point of body 1's surface from body 2): 1000 Fibonacci-sphere samples w, surface points
  !> X1 + R1 diag(a, b, b) w (a pole-free parametrisation), exact distance to body 2; the best 3
  !> samples refined by finite-difference Newton steps in a local tangent chart of w.
  function brute_force_gap(body1, centre1, rotation1, body2, centre2, rotation2) result(best)
    type(spheroid_t), intent(in) :: body1, body2
    real(wp), intent(in) :: centre1(3), rotation1(3,3), centre2(3), rotation2(3,3)
    real(wp) :: best
    integer, parameter :: n_samples = 1000, n_seeds = 3
    real(wp) :: w(3), f, seed_f(n_seeds), seed_w(3, n_seeds), golden, z, rho
    integer :: j, s, worst_seed
    b1 = body1; b2 = body2; x1 = centre1; x2 = centre2; r1 = rotation1; r2 = rotation2
    golden = pi * (3.0_wp - sqrt(5.0_wp))
    seed_f = huge(1.0_wp)
    seed_w = 0.0_wp
    do j = 0, n_samples - 1
      z = 1.0_wp - (2.0_wp * j + 1.0_wp) / n_samples
      rho = sqrt(1.0_wp - z * z)
      w = [z, rho * cos(golden * j), rho * sin(golden * j)]
      f = sample_distance(w)
      worst_seed = maxloc(seed_f, 1)
      if (f < seed_f(worst_seed)) then
        seed_f(worst_seed) = f
        seed_w(:, worst_seed) = w
      end if
    end do
    best = huge(1.0_wp)
    do s = 1, n_seeds
      best = min(best, refine(seed_w(:, s)))
    end do
  end function brute_force_gap

  function sample_distance(v) result(d)
      real(wp), intent(in) :: v(3)
      real(wp) :: d
      d = point_body_distance(b2, x2, r2, x1 + matmul(r1, [b1%a, b1%b, b1%b] * v / norm2(v)))
  end function sample_distance

    function refine(w_start) result(f_best)
      real(wp), intent(in) :: w_start(3)
      real(wp) :: f_best, w0(3), t1(3), t2(3), h, fs(-1:1, -1:1), g(2), hm(2,2), det, step(2), f_try
      real(wp) :: axis(3), best_offset(2)
      integer :: it, i1, i2
      w0 = w_start
      h = 0.03_wp
      f_best = sample_distance(w0)
      do it = 1, 100
        axis = 0.0_wp
        axis(minloc(abs(w0), 1)) = 1.0_wp
        t1 = cross(w0, axis); t1 = t1 / norm2(t1)
        t2 = cross(w0, t1)
        best_offset = 0.0_wp
        do i2 = -1, 1
          do i1 = -1, 1
            if (i1 == 0 .and. i2 == 0) then
              fs(0, 0) = f_best
            else
              fs(i1, i2) = sample_distance(w0 + h * (i1 * t1 + i2 * t2))
            end if
          end do
        end do
        g = [fs(1, 0) - fs(-1, 0), fs(0, 1) - fs(0, -1)] / (2 * h)
        hm(1,1) = (fs(1, 0) - 2 * fs(0, 0) + fs(-1, 0)) / h**2
        hm(2,2) = (fs(0, 1) - 2 * fs(0, 0) + fs(0, -1)) / h**2
        hm(1,2) = (fs(1, 1) - fs(1, -1) - fs(-1, 1) + fs(-1, -1)) / (4 * h**2)
        hm(2,1) = hm(1,2)
        det = hm(1,1) * hm(2,2) - hm(1,2)**2
        if (det > 0 .and. hm(1,1) > 0) then
          step = -[hm(2,2) * g(1) - hm(1,2) * g(2), hm(1,1) * g(2) - hm(1,2) * g(1)] / det
        else
          step = -h * g / max(norm2(g), tiny(1.0_wp))
        end if
        if (norm2(step) > 3 * h) step = step * (3 * h / norm2(step))
        ! Move to the best of the stencil and the Newton point.
        do i2 = -1, 1
          do i1 = -1, 1
            if (fs(i1, i2) < f_best) then
              f_best = fs(i1, i2)
              best_offset = h * [i1, i2]
            end if
          end do
        end do
        f_try = sample_distance(w0 + step(1) * t1 + step(2) * t2)
        if (f_try < f_best) then
          f_best = f_try
          best_offset = step
        end if
        w0 = w0 + best_offset(1) * t1 + best_offset(2) * t2
        w0 = w0 / norm2(w0)
        if (norm2(best_offset) == 0.0_wp) then
          h = 0.25_wp * h
        else
          h = min(h, max(norm2(step), 0.1_wp * h, 1.0e-7_wp))
        end if
        if (h < 1.0e-11_wp .or. (norm2(best_offset) < 1.0e-12_wp .and. h <= 1.0e-7_wp)) exit
      end do
    end function refine

end module brute_force_distance
