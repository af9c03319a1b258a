! checks: 18
!> Tests of spheroid_distance: point-to-spheroid closest point, normal and signed distance against an
!> independent brute-force reference (dense Fibonacci sampling of the whole 3-D surface, then a
!> Newton polish of the Lagrange conditions X - p + lambda D X = 0, X.D X = 1 with D = diag(a, b, b)^-2,
!> from the best samples; it uses neither the meridian-plane reduction nor the bisection; for points
!> within 1e-6 r of the axis, where that system is singular along the circle of symmetry, dense
!> sampling and Newton in the meridian angle instead), for points inside and outside, near the
!> surface, near and on the axis, at the centre, for spheres, needles and disks of aspect ratio 5
!> and 20 and near-spheres. Tolerance 1e-12 r (docs/theory.md,
!> "Immersed boundary geometry"; the immersed-boundary validation ladder, rung 1).
program test_spheroid_distance
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation, rotate_to_lab
  use spheroid, only: spheroid_t, make_spheroid, implicit_function, normal_at_point, surface_point
  use spheroid_distance, only: surface_projection_t, body_closest_point, lab_closest_point, ellipse_closest_point
  use wall_clock, only: wall_time
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp
  integer, parameter :: n_shapes = 7, n_samples = 20000, n_seeds = 6
  type(spheroid_t) :: shapes(n_shapes)
  character(len=12) :: names(n_shapes)
  type(random_stream_t) :: stream
  type(surface_projection_t) :: proj, proj_body
  real(wp) :: samples(3, n_samples)
  real(wp) :: p(3), reference, worst_distance, worst_point, worst_surface, worst_normal, worst_stationary
  real(wp) :: x_ref(3), centre(3), q(4), t0, elapsed, x0, x1, d2
  real(wp) :: worst_near, worst_axis, worst_lab
  integer :: s, k, n_points, n_wrong_sign, n_timed
  logical :: unique

  call test_start('spheroid_distance')
  call stream_seed(stream, 2013_i8, stream_id=5)
  shapes = [make_spheroid('sphere', radius, density), make_spheroid('needle', radius, density), &
            make_spheroid('disk', radius, density), make_spheroid('needle', radius, density, 20.0_wp), &
            make_spheroid('disk', radius, density, 20.0_wp), make_spheroid('spheroid', radius, density, 1.0001_wp), &
            make_spheroid('spheroid', radius, density, 0.9999_wp)]
  names = [character(len=12) :: 'sphere', 'needle5', 'disk5', 'needle20', 'disk20', 'near_prolate', 'near_oblate']

  ! --- Exact cases (closed form).
  ! Centre: the distance is minus the smaller semi-axis (docs/theory.md).
  proj = body_closest_point(shapes(2), [0.0_wp, 0.0_wp, 0.0_wp])
  call check_close(proj%signed_distance, -shapes(2)%b, 1.0e-15_wp, 'needle_centre_minus_b')
  proj = body_closest_point(shapes(3), [0.0_wp, 0.0_wp, 0.0_wp])
  call check_close(proj%signed_distance, -shapes(3)%a, 1.0e-15_wp, 'disk_centre_minus_a')
  proj = body_closest_point(shapes(1), [0.0_wp, 0.0_wp, 0.0_wp])
  call check_close(proj%signed_distance, -radius, 1.0e-15_wp, 'sphere_centre_minus_r')
  ! On the axis outside: the pole, distance x - a; on the axis inside a disk: the pole, a - |x|.
  proj = body_closest_point(shapes(4), [-3.0_wp * shapes(4)%a, 0.0_wp, 0.0_wp])
  call check_close(proj%signed_distance, 2.0_wp * shapes(4)%a, 1.0e-15_wp, 'needle20_axis_outside_pole')
  call check_below(norm2(proj%normal - [-1.0_wp, 0.0_wp, 0.0_wp]), 1.0e-15_wp, 'needle20_axis_outside_normal')
  proj = body_closest_point(shapes(5), [0.3_wp * shapes(5)%a, 0.0_wp, 0.0_wp])
  call check_close(proj%signed_distance, -0.7_wp * shapes(5)%a, 1.0e-14_wp, 'disk20_axis_inside_pole')
  ! Needle axis inside the evolute (|x| < (a^2 - b^2)/a): the closest points form a circle at
  ! x_B = a^2 |x|/(a^2 - b^2), radius b sqrt(1 - x_B^2/a^2) (Eberly 2013, the case y1 = 0).
  p = [0.4_wp * shapes(2)%a, 0.0_wp, 0.0_wp]
  proj = body_closest_point(shapes(2), p)
  x0 = shapes(2)%a**2 * p(1) / (shapes(2)%a**2 - shapes(2)%b**2)
  x1 = shapes(2)%b * sqrt(1.0_wp - (x0 / shapes(2)%a)**2)
  call check_close(proj%signed_distance, -hypot(x0 - p(1), x1), 1.0e-14_wp, 'needle_axis_inside_evolute_circle')
  ! Sphere: distance |p| - r along the radius, to round-off.
  worst_distance = 0.0_wp
  do k = 1, 200
    p = radius * 3.0_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] - 1.5_wp * radius
    proj = body_closest_point(shapes(1), p)
    worst_distance = max(worst_distance, abs(proj%signed_distance - (norm2(p) - radius)) / radius, &
                         norm2(proj%point - radius * p / norm2(p)) / radius)
  end do
  call check_below(worst_distance, 4.0e-16_wp * 8, 'sphere_radial_projection_exact')
  ! The 2-D kernel on the ellipse's own surface returns the point itself.
  call ellipse_closest_point(2.0_wp, 1.0_wp, sqrt(2.0_wp), sqrt(0.5_wp), x0, x1, d2)
  call check_below(d2, 1.0e-15_wp, 'ellipse_point_on_curve_distance_zero')

  ! --- Against the brute-force reference.
  n_points = 0
  n_wrong_sign = 0
  worst_distance = 0.0_wp; worst_point = 0.0_wp; worst_surface = 0.0_wp; worst_normal = 0.0_wp
  worst_stationary = 0.0_wp; worst_near = 0.0_wp; worst_axis = 0.0_wp
  do s = 1, n_shapes
    call fill_samples(shapes(s))
    do k = 1, 120
      p = random_point(shapes(s), k)
      proj = body_closest_point(shapes(s), p)
      if (hypot(p(2), p(3)) < 1.0e-6_wp * radius) then
        call meridian_reference(shapes(s), p, reference)
        unique = .false.
      else
        call brute_force(shapes(s), p, x_ref, reference, unique)
      end if
      n_points = n_points + 1
      if ((implicit_function(shapes(s), p) < 0.0_wp) .neqv. (proj%signed_distance < 0.0_wp)) then
        if (abs(proj%signed_distance) > 1.0e-15_wp * radius) n_wrong_sign = n_wrong_sign + 1
      end if
      select case (mod(k, 6))
      case (2)
        worst_near = max(worst_near, abs(abs(proj%signed_distance) - reference) / radius)
      case (3, 4)
        worst_axis = max(worst_axis, abs(abs(proj%signed_distance) - reference) / radius)
      case default
        worst_distance = max(worst_distance, abs(abs(proj%signed_distance) - reference) / radius)
      end select
      if (unique .and. mod(k, 6) <= 2) then
        worst_point = max(worst_point, norm2(proj%point - x_ref) / radius)
      end if
      ! The returned point is on the surface, the normal is the unit implicit gradient there, and
      ! p - B is along the normal with length |d| (the Lagrange conditions of the minimum).
      worst_surface = max(worst_surface, abs(implicit_function(shapes(s), proj%point)))
      worst_normal = max(worst_normal, norm2(proj%normal - normal_at_point(shapes(s), proj%point)), &
                         abs(norm2(proj%normal) - 1.0_wp))
      worst_stationary = max(worst_stationary, &
                             norm2(p - proj%point - proj%signed_distance * proj%normal) / radius)
    end do
  end do
  call check_below(worst_distance, 1.0e-12_wp, 'random_inside_outside_distance_vs_brute_force')
  call check_below(worst_near, 1.0e-12_wp, 'near_surface_distance_vs_brute_force')
  call check_below(worst_axis, 1.0e-12_wp, 'near_and_on_axis_distance_vs_brute_force')
  call check_below(worst_point, 1.0e-12_wp, 'closest_point_vs_brute_force_where_unique')
  call check_below(worst_surface, 1.0e-14_wp, 'closest_point_on_surface')
  call check_below(worst_normal, 1.0e-14_wp, 'normal_unit_implicit_gradient')
  call check_below(worst_stationary, 1.0e-12_wp, 'p_minus_B_is_d_times_n')
  call check(n_wrong_sign == 0, 'sign_negative_inside', 'points with the wrong sign counted')
  write(*, '(a,i0,a,3es10.2)') 'brute-force comparison: ', n_points, ' points; max |d - d_ref|/r (random, near, axis): ', &
      worst_distance, worst_near, worst_axis

  ! --- Lab frame: rotation and translation commute with the projection.
  worst_lab = 0.0_wp
  do k = 1, 200
    s = mod(k, n_shapes) + 1
    q = random_orientation(stream)
    centre = 1.0e-3_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    p = random_point(shapes(s), 6 * k + mod(k, 3))    ! off the axis: a unique closest point
    proj_body = body_closest_point(shapes(s), p)
    proj = lab_closest_point(shapes(s), centre, q, centre + rotate_to_lab(q, p))
    worst_lab = max(worst_lab, abs(proj%signed_distance - proj_body%signed_distance) / radius, &
                    norm2(proj%point - centre - rotate_to_lab(q, proj_body%point)) / radius, &
                    norm2(proj%normal - rotate_to_lab(q, proj_body%normal)))
  end do
  ! The lab point carries the round-off of |centre| ~ 1e-3 m = 20 r: a few ulps of that.
  call check_below(worst_lab, 1.0e-12_wp, 'lab_frame_equals_rotated_body_frame')

  ! Cost (reported, not asserted).
  n_timed = 0
  t0 = wall_time()
  do k = 1, 100000
    s = mod(k, n_shapes) + 1
    proj = body_closest_point(shapes(s), radius * [0.9_wp + 1.0e-6_wp * k, 0.2_wp, -0.1_wp])
    if (proj%signed_distance > 1.0_wp) n_timed = n_timed + 1
  end do
  elapsed = wall_time() - t0
  write(*, '(a,f8.3,a)') 'cost: ', 1.0e9_wp * elapsed / 100000, ' ns per projection'
  call test_finish()

contains

  !> A test point for case k: random in the box around the body, near the surface (|d| from 1e-12 r
  !> to 1e-2 r on either side), near the axis (radial offset 1e-12 r to 1e-4 r), on the axis
  !> exactly, in the equatorial plane exactly, or at a tiny offset from the centre.
  function random_point(body, k) result(p)
    type(spheroid_t), intent(in) :: body
    integer, intent(in) :: k
    real(wp) :: p(3), theta, phi, offset, extent(3), direction(3)
    extent = [body%a, body%b, body%b]
    select case (mod(k, 6))
    case (0, 1)
      p = extent * (3.0_wp * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] - 1.5_wp)
      if (mod(k, 12) == 0) p = 0.9_wp * p / 1.5_wp    ! mostly inside
    case (2)
      theta = pi * stream_uniform(stream)
      phi = pi * (2.0_wp * stream_uniform(stream) - 1.0_wp)
      offset = radius * 10.0_wp**(-12.0_wp + 10.0_wp * stream_uniform(stream))
      if (stream_uniform(stream) < 0.5_wp) offset = -offset
      p = surface_point(body, theta, phi)
      p = p + offset * normal_at_point(body, p)
    case (3)
      direction = [0.0_wp, stream_normal(stream), stream_normal(stream)]
      p = [body%a * (3.0_wp * stream_uniform(stream) - 1.5_wp), 0.0_wp, 0.0_wp] &
        + radius * 10.0_wp**(-12.0_wp + 8.0_wp * stream_uniform(stream)) * direction / norm2(direction)
    case (4)
      if (mod(k, 12) == 4) then
        p = [body%a * (3.0_wp * stream_uniform(stream) - 1.5_wp), 0.0_wp, 0.0_wp]
      else
        direction = [0.0_wp, stream_normal(stream), stream_normal(stream)]
        p = body%b * (3.0_wp * stream_uniform(stream)) * direction / norm2(direction)
      end if
    case default
      direction = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      p = radius * 10.0_wp**(-8.0_wp + 7.0_wp * stream_uniform(stream)) * direction / norm2(direction)
    end select
  end function random_point

  !> 20000 Fibonacci points on the unit sphere mapped to the surface by diag(a, b, b).
  subroutine fill_samples(body)
    type(spheroid_t), intent(in) :: body
    real(wp) :: golden, z, rho
    integer :: j
    golden = pi * (3.0_wp - sqrt(5.0_wp))
    do j = 0, n_samples - 1
      z = 1.0_wp - (2.0_wp * j + 1.0_wp) / n_samples
      rho = sqrt(1.0_wp - z * z)
      samples(:, j + 1) = [body%a * z, body%b * rho * cos(golden * j), body%b * rho * sin(golden * j)]
    end do
  end subroutine fill_samples

  !> Brute-force closest point: the n_seeds best samples, each polished by Newton on the Lagrange
  !> system; the smallest distance wins. `unique` is false when two polished candidates with
  !> distances within 1e-9 r lie apart (a circle or pair of closest points).
  subroutine brute_force(body, p, x_best, d_best, unique)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: p(3)
    real(wp), intent(out) :: x_best(3), d_best
    logical, intent(out) :: unique
    real(wp) :: seed_d(n_seeds), seed_x(3, n_seeds), d, x(3)
    integer :: j, worst_seed
    seed_d = huge(1.0_wp)
    seed_x = 0.0_wp
    do j = 1, n_samples
      d = norm2(samples(:, j) - p)
      worst_seed = maxloc(seed_d, 1)
      if (d < seed_d(worst_seed)) then
        seed_d(worst_seed) = d
        seed_x(:, worst_seed) = samples(:, j)
      end if
    end do
    d_best = huge(1.0_wp)
    unique = .true.
    do j = 1, n_seeds
      x = newton_polish(body, p, seed_x(:, j))
      d = norm2(x - p)
      if (abs(d - d_best) < 1.0e-9_wp * radius .and. norm2(x - x_best) > 1.0e-6_wp * radius) unique = .false.
      if (d < d_best) then
        if (d_best - d < 1.0e-9_wp * radius .and. norm2(x - x_best) > 1.0e-6_wp * radius) unique = .false.
        d_best = d
        x_best = x
      end if
    end do
  end subroutine brute_force

  !> Newton on R(X, lambda) = (X - p + lambda D X, (X.D X - 1)/2) = 0, D = diag(1/a^2, 1/b^2, 1/b^2).
  function newton_polish(body, p, x_start) result(x)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: p(3), x_start(3)
    real(wp) :: x(3), dd(3), lambda, jac(4, 4), rhs(4), step(4), gx(3)
    integer :: it, i
    dd = [1.0_wp / body%a**2, 1.0_wp / body%b**2, 1.0_wp / body%b**2]
    x = x_start
    gx = dd * x
    lambda = -dot_product(x - p, gx) / dot_product(gx, gx)
    do it = 1, 60
      gx = dd * x
      rhs(1:3) = -(x - p + lambda * gx)
      rhs(4) = -0.5_wp * (dot_product(x, gx) - 1.0_wp)
      jac = 0.0_wp
      do i = 1, 3
        jac(i, i) = 1.0_wp + lambda * dd(i)
        jac(i, 4) = gx(i)
        jac(4, i) = gx(i)
      end do
      step = solve4(jac, rhs)
      x = x + step(1:3)
      lambda = lambda + step(4)
      if (norm2(step(1:3)) < 1.0e-17_wp * radius) exit
    end do
  end function newton_polish

  !> Reference for points on or within 1e-6 r of the axis, where the 3-D Lagrange system is
  !> (nearly) singular along the circle of symmetry: by that symmetry the closest point lies in the
  !> meridian plane through p, and the distance from (u, w) = (|x|, sqrt(y^2 + z^2)) to the curve
  !> (a cos phi, b sin phi), phi in [0, pi], is minimised by dense sampling of phi and Newton on
  !> df/dphi = 0 from the best samples (no bisection, no Eberly parametrisation).
  subroutine meridian_reference(body, p, d_best)
    type(spheroid_t), intent(in) :: body
    real(wp), intent(in) :: p(3)
    real(wp), intent(out) :: d_best
    integer, parameter :: n_phi = 20000
    real(wp) :: u, w, phi, f, best_phi(3), best_f(3), g, dg, a, b
    integer :: j, it, worst, seed
    a = body%a; b = body%b
    u = abs(p(1)); w = hypot(p(2), p(3))
    best_f = huge(1.0_wp); best_phi = 0.0_wp
    do j = 0, n_phi
      phi = pi * j / n_phi
      f = (a * cos(phi) - u)**2 + (b * sin(phi) - w)**2
      worst = maxloc(best_f, 1)
      if (f < best_f(worst)) then
        best_f(worst) = f; best_phi(worst) = phi
      end if
    end do
    d_best = huge(1.0_wp)
    do seed = 1, 3
      phi = best_phi(seed)
      do it = 1, 50
        g = -a * sin(phi) * (a * cos(phi) - u) + b * cos(phi) * (b * sin(phi) - w)
        dg = -a * cos(phi) * (a * cos(phi) - u) + (a * sin(phi))**2 - b * sin(phi) * (b * sin(phi) - w) &
             + (b * cos(phi))**2
        if (dg <= 0.0_wp) exit
        phi = phi - g / dg
      end do
      d_best = min(d_best, hypot(a * cos(phi) - u, b * sin(phi) - w), sqrt(best_f(seed)))
    end do
  end subroutine meridian_reference

  !> 4x4 linear solve by Gaussian elimination with partial pivoting.
  function solve4(a_in, b_in) result(x)
    real(wp), intent(in) :: a_in(4, 4), b_in(4)
    real(wp) :: x(4), a(4, 4), b(4), row(4), factor, temp
    integer :: i, j, pivot
    a = a_in; b = b_in
    do i = 1, 4
      pivot = i - 1 + maxloc(abs(a(i:4, i)), 1)
      if (pivot /= i) then
        row = a(i, :); a(i, :) = a(pivot, :); a(pivot, :) = row
        temp = b(i); b(i) = b(pivot); b(pivot) = temp
      end if
      do j = i + 1, 4
        factor = a(j, i) / a(i, i)
        a(j, i:4) = a(j, i:4) - factor * a(i, i:4)
        b(j) = b(j) - factor * b(i)
      end do
    end do
    do i = 4, 1, -1
      x(i) = (b(i) - dot_product(a(i, i + 1:4), x(i + 1:4))) / a(i, i)
    end do
  end function solve4

end program test_spheroid_distance
