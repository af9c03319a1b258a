! checks: 81
!> Unit tests of spheroid: semi-axes of the paper's shapes, mass and inertia against slice-wise
!> quadrature of the solid, area against quadrature of the surface, principal curvatures and
!> directions against finite differences of the parametric surface, pole/equator values, the
!> inverse map (incl. poles), the implicit function and the normal-to-point (support) map.
program test_spheroid
  use agglo_kinds, only: wp, i8
  use vector_algebra, only: cross
  use physical_constants, only: pi
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use spheroid, only: spheroid_t, make_spheroid, surface_point, surface_normal, principal_curvatures, &
                      principal_directions, surface_angles, implicit_function, implicit_gradient, &
                      normal_at_point, support_point, support_value, surface_area
  use test_framework, only: test_start, test_finish, check_close, check_below
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp   ! calcite, Table 1 of the paper
  type(spheroid_t) :: needle, disk, sphere, shapes(6)
  type(random_stream_t) :: stream
  real(wp) :: km, kp, mass_q, ix_q, iy_q, area_q, worst, theta, phi, theta_back, phi_back, p(3), m(3), y(3)
  real(wp) :: worst_angle, worst_point, worst_dir
  integer :: i, k
  character(len=32) :: label

  call test_start('spheroid')
  call stream_seed(stream, 77_i8, stream_id=3)
  needle = make_spheroid('needle', radius, density)
  disk = make_spheroid('disk', radius, density)
  sphere = make_spheroid('sphere', radius, density)

  ! docs/physics.md section 0: aspect ratio 5, r = 50 um: needle a = 146.2 um, b = 29.24 um;
  ! disk a = 17.10 um, b = 85.50 um (4 significant figures given there).
  call check_close(needle%a, 146.2e-6_wp, 5.0e-4_wp, 'needle_a_146.2um')
  call check_close(needle%b, 29.24e-6_wp, 5.0e-4_wp, 'needle_b_29.24um')
  call check_close(disk%a, 17.10e-6_wp, 5.0e-4_wp, 'disk_a_17.10um')
  call check_close(disk%b, 85.50e-6_wp, 5.0e-4_wp, 'disk_b_85.50um')
  call check_close(needle%a * needle%b**2, radius**3, 1.0e-14_wp, 'needle_volume_equivalent')
  call check_close(disk%a / disk%b, 0.2_wp, 1.0e-14_wp, 'disk_aspect_ratio_one_fifth')

  shapes = [needle, disk, sphere, make_spheroid('spheroid', radius, density, 20.0_wp), &
            make_spheroid('spheroid', radius, density, 0.05_wp), make_spheroid('spheroid', radius, density, 1.0001_wp)]

  ! Mass and inertia (Eq. 12 with b = c) against Simpson quadrature over slices x = const of the
  ! solid: a slice is a disc of radius rho(x) = b sqrt(1 - x^2/a^2), with polar moment
  ! pi rho^4/2 and diameter moment pi rho^4/4 (per unit density and thickness).
  do i = 1, size(shapes)
    call slice_quadrature(shapes(i), mass_q, ix_q, iy_q)
    write(label, '(a,f0.4)') 'ar_', shapes(i)%aspect_ratio
    call check_close(shapes(i)%mass, mass_q, 1.0e-10_wp, 'mass_vs_quadrature_'//trim(label))
    call check_close(shapes(i)%inertia(1), ix_q, 1.0e-10_wp, 'inertia_axial_vs_quadrature_'//trim(label))
    call check_close(shapes(i)%inertia(2), iy_q, 1.0e-10_wp, 'inertia_transverse_vs_quadrature_'//trim(label))
    call check_close(shapes(i)%inertia(3), iy_q, 1.0e-10_wp, 'inertia_z_equals_y_'//trim(label))
    ! Area: dA = |X_theta x X_phi| dtheta dphi = b |sin phi| sqrt(a^2 sin^2 phi + b^2 cos^2 phi),
    ! independent of theta: A = 2 pi int_0^pi b sin(phi) sqrt(...) dphi (Simpson, 20000 panels).
    area_q = area_quadrature(shapes(i))
    call check_close(surface_area(shapes(i)), area_q, 1.0e-12_wp, 'area_vs_quadrature_'//trim(label))
  end do
  call check_close(surface_area(sphere), 4*pi*radius**2, 1.0e-14_wp, 'sphere_area')

  ! Pole and equator curvatures, docs/physics.md section 1: pole both a/b^2; equator kappa_m = b/a^2,
  ! kappa_p = 1/b; sphere 1/r.
  do i = 1, size(shapes)
    write(label, '(a,f0.4)') 'ar_', shapes(i)%aspect_ratio
    call principal_curvatures(shapes(i), 0.0_wp, km, kp)
    call check_close(km, shapes(i)%a / shapes(i)%b**2, 1.0e-14_wp, 'pole_kappa_meridional_'//trim(label))
    call check_close(kp, shapes(i)%a / shapes(i)%b**2, 1.0e-14_wp, 'pole_kappa_parallel_'//trim(label))
    call principal_curvatures(shapes(i), 0.5_wp*pi, km, kp)
    call check_close(km, shapes(i)%b / shapes(i)%a**2, 1.0e-14_wp, 'equator_kappa_meridional_'//trim(label))
    call check_close(kp, 1.0_wp / shapes(i)%b, 1.0e-14_wp, 'equator_kappa_parallel_'//trim(label))
  end do
  call principal_curvatures(sphere, 0.9_wp, km, kp)
  call check_close(km, 1.0_wp / radius, 1.0e-14_wp, 'sphere_kappa_meridional')
  call check_close(kp, 1.0_wp / radius, 1.0e-14_wp, 'sphere_kappa_parallel')

  ! Curvatures and directions against finite differences of surface_point (away from the poles,
  ! where the parametrisation is singular): kappa along a line of curvature = X_ss . n / |X_s|^2
  ! (second fundamental form over the first); the parameter lines are lines of curvature, so
  ! F = X_theta . X_phi = 0 and M = X_theta_phi . n = 0.
  do i = 1, size(shapes)
    write(label, '(a,f0.4)') 'ar_', shapes(i)%aspect_ratio
    call curvature_finite_differences(shapes(i), worst, worst_dir)
    ! Central differences, step 1e-3 rad: truncation ~ h^2/12 ~ 1e-7, round-off ~ 1e-16/h^2 = 1e-10.
    call check_below(worst, 1.0e-6_wp, 'curvatures_vs_finite_differences_'//trim(label))
    ! First differences of the tangents: their O(h^2) error is parallel to the tangent (X''' = -X' for
    ! these trigonometric parameter lines), so the normalised directions agree to round-off / h.
    call check_below(worst_dir, 1.0e-10_wp, 'principal_directions_vs_finite_differences_'//trim(label))
  end do

  ! Inverse map round trip: random angles, the poles, theta = 0 and pi, the equator, phi < 0.
  worst_angle = 0.0_wp
  worst_point = 0.0_wp
  do i = 1, size(shapes)
    do k = 1, 2000
      theta = pi * stream_uniform(stream)
      phi = pi * (2.0_wp * stream_uniform(stream) - 1.0_wp)
      select case (k)
      case (1); theta = 0.0_wp; phi = 0.0_wp
      case (2); theta = 0.0_wp; phi = pi
      case (3); theta = 0.0_wp; phi = -0.5_wp*pi
      case (4); theta = pi; phi = 0.5_wp*pi
      case (5); theta = 0.0_wp; phi = 1.0_wp
      case (6); theta = 0.0_wp; phi = -1.0_wp
      case (7); theta = 0.5_wp*pi; phi = -2.5_wp
      case (8); theta = 1.3_wp; phi = 1.0e-12_wp
      end select
      p = surface_point(shapes(i), theta, phi)
      call surface_angles(shapes(i), p, theta_back, phi_back)
      worst_point = max(worst_point, norm2(surface_point(shapes(i), theta_back, phi_back) - p) / shapes(i)%radius)
      if (theta_back < 0.0_wp .or. theta_back > pi .or. phi_back <= -pi .or. phi_back > pi) worst_point = huge(1.0_wp)
      ! Angles are unique away from the poles (sin(phi) /= 0) and from theta = 0, pi with the
      ! sign of phi ambiguous at z = 0 (both (0, phi) and (pi, -phi) give the point).
      if (abs(sin(phi)) > 1.0e-6_wp .and. theta > 1.0e-6_wp .and. theta < pi - 1.0e-6_wp) then
        worst_angle = max(worst_angle, abs(theta_back - theta), abs(phi_back - phi))
      end if
    end do
  end do
  call check_below(worst_point, 1.0e-15_wp * 8, 'inverse_map_round_trip_points')
  call check_below(worst_angle, 1.0e-12_wp, 'inverse_map_round_trip_angles')
  call surface_angles(needle, [needle%a, 0.0_wp, 0.0_wp], theta, phi)
  call check_below(abs(theta) + abs(phi), 0.0_wp, 'inverse_map_pole_plus_x')
  call surface_angles(needle, [-needle%a, 0.0_wp, 0.0_wp], theta, phi)
  call check_below(abs(theta) + abs(phi - pi), 0.0_wp, 'inverse_map_pole_minus_x_is_pi')

  ! Implicit function zero on the surface, gradient along the parametric normal; the normal-to-point
  ! map gives a surface point whose outward normal is m and which maximises p.m (support point).
  worst = 0.0_wp
  worst_dir = 0.0_wp
  do i = 1, size(shapes)
    do k = 1, 500
      theta = pi * stream_uniform(stream)
      phi = pi * (2.0_wp * stream_uniform(stream) - 1.0_wp)
      p = surface_point(shapes(i), theta, phi)
      worst = max(worst, abs(implicit_function(shapes(i), p)))
      worst_dir = max(worst_dir, norm2(normal_at_point(shapes(i), p) - surface_normal(shapes(i), theta, phi)), &
                      norm2(implicit_gradient(shapes(i), p) / norm2(implicit_gradient(shapes(i), p)) - &
                            surface_normal(shapes(i), theta, phi)))
      m = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
      m = m / norm2(m)
      y = support_point(shapes(i), m)
      worst = max(worst, abs(implicit_function(shapes(i), y)))
      worst_dir = max(worst_dir, norm2(normal_at_point(shapes(i), y) - m))
      ! No surface point lies further along m than the support point.
      if (dot_product(p, m) > dot_product(y, m) * (1 + 1.0e-15_wp)) worst_dir = 1.0_wp
      worst = max(worst, abs(dot_product(y, m) - support_value(shapes(i), m)) / shapes(i)%radius)
    end do
  end do
  call check_below(worst, 1.0e-14_wp, 'implicit_function_zero_and_support_value')
  call check_below(worst_dir, 1.0e-14_wp, 'normal_gradient_and_support_point_normal')

  call test_finish()

contains

  subroutine slice_quadrature(s, mass, ix, iy)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(out) :: mass, ix, iy
    integer, parameter :: panels = 2000
    integer :: j
    real(wp) :: x, h, wgt, rho2
    mass = 0; ix = 0; iy = 0
    h = 2.0_wp * s%a / panels
    do j = 0, panels
      x = -s%a + j * h
      wgt = merge(1.0_wp, merge(4.0_wp, 2.0_wp, mod(j, 2) == 1), j == 0 .or. j == panels) * h / 3.0_wp
      rho2 = max(0.0_wp, s%b**2 * (1.0_wp - (x / s%a)**2))
      mass = mass + wgt * pi * rho2
      ix = ix + wgt * 0.5_wp * pi * rho2**2
      iy = iy + wgt * (0.25_wp * pi * rho2**2 + x**2 * pi * rho2)
    end do
    mass = s%density * mass
    ix = s%density * ix
    iy = s%density * iy
  end subroutine slice_quadrature

  function area_quadrature(s) result(area)
    type(spheroid_t), intent(in) :: s
    real(wp) :: area, h, f, wgt, t
    integer, parameter :: panels = 20000
    integer :: j
    area = 0
    h = pi / panels
    do j = 0, panels
      t = j * h
      wgt = merge(1.0_wp, merge(4.0_wp, 2.0_wp, mod(j, 2) == 1), j == 0 .or. j == panels) * h / 3.0_wp
      f = s%b * sin(t) * sqrt((s%a * sin(t))**2 + (s%b * cos(t))**2)
      area = area + wgt * f
    end do
    area = 2.0_wp * pi * area
  end function area_quadrature

  subroutine curvature_finite_differences(s, worst_rel, worst_direction)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(out) :: worst_rel, worst_direction
    real(wp), parameter :: h = 1.0e-3_wp
    real(wp) :: xt(3), xp(3), xtt(3), xpp(3), xtp(3), n(3), km_fd, kp_fd, km_a, kp_a, tm(3), tp(3), t, f
    integer :: it, ip
    worst_rel = 0.0_wp
    worst_direction = 0.0_wp
    do it = 0, 6
      do ip = -7, 7
        if (ip == 0) cycle
        t = it * pi / 6.0_wp
        f = ip * pi / 7.5_wp
        xt = (surface_point(s, t + h, f) - surface_point(s, t - h, f)) / (2*h)
        xp = (surface_point(s, t, f + h) - surface_point(s, t, f - h)) / (2*h)
        xtt = (surface_point(s, t + h, f) - 2*surface_point(s, t, f) + surface_point(s, t - h, f)) / h**2
        xpp = (surface_point(s, t, f + h) - 2*surface_point(s, t, f) + surface_point(s, t, f - h)) / h**2
        xtp = (surface_point(s, t + h, f + h) - surface_point(s, t + h, f - h) - surface_point(s, t - h, f + h) &
               + surface_point(s, t - h, f - h)) / (4*h**2)
        n = surface_normal(s, t, f)
        ! Convex surface, outward normal: the second derivatives point inwards.
        km_fd = -dot_product(xpp, n) / dot_product(xp, xp)
        kp_fd = -dot_product(xtt, n) / dot_product(xt, xt)
        call principal_curvatures(s, f, km_a, kp_a)
        worst_rel = max(worst_rel, abs(km_fd - km_a) / km_a, abs(kp_fd - kp_a) / kp_a, &
                        abs(dot_product(xtp, n)) / norm2(xt) / norm2(xp) / kp_a, &
                        abs(dot_product(xt, xp)) / norm2(xt) / norm2(xp))
        call principal_directions(s, t, f, tm, tp)
        ! Directions up to the O(h^2) error of the first differences: tangents normalised.
        worst_direction = max(worst_direction, norm2(tm - xp / norm2(xp)), &
                              norm2(tp - sign(1.0_wp, sin(f)) * xt / norm2(xt)), &
                              norm2(cross(tm, tp) - n))
      end do
    end do
  end subroutine curvature_finite_differences

end program test_spheroid
