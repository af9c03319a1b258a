!> Analytic spheroid geometry in the body frame (docs/physics.md sections 0 and 1).
!> The symmetry axis is body x with semi-axis a; the other two semi-axes are b (= c).
!> Needle: a > b (prolate); disk: a < b (oblate); sphere: a = b. Volume-equivalent radius r: a b^2 = r^3.
!> Parametric surface angles (the paper's Figs. 5-7): x = a cos(phi), y = b sin(phi) cos(theta),
!> z = b sin(phi) sin(theta), theta in [0, pi], phi in (-pi, pi]; phi = 0 is the pole on +x.
!> Mass, volume and inertia come from this analytic shape, never from the triangle mesh.
module spheroid
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use error_handling, only: fatal
  implicit none
  private
  public :: spheroid_t, make_spheroid, default_aspect_ratio, &
            surface_point, surface_normal, principal_curvatures, principal_directions, &
            surface_angles, implicit_function, implicit_gradient, normal_at_point, &
            support_point, support_value, surface_area

  real(wp), parameter :: default_aspect_ratio = 5.0_wp   !< the paper's needles and disks (section 2.2.1)

  type :: spheroid_t
    character(len=16) :: shape = 'sphere'   !< 'sphere' | 'needle' | 'disk' | 'spheroid'
    real(wp) :: a = 0.0_wp             !< m, semi-axis along the symmetry axis (body x)
    real(wp) :: b = 0.0_wp             !< m, the two equal semi-axes (body y and z)
    real(wp) :: radius = 0.0_wp        !< m, volume-equivalent radius r, a b^2 = r^3
    real(wp) :: aspect_ratio = 1.0_wp  !< a/b (> 1 needle, < 1 disk)
    real(wp) :: density = 0.0_wp       !< kg/m^3
    real(wp) :: volume = 0.0_wp        !< m^3, 4/3 pi a b^2
    real(wp) :: mass = 0.0_wp          !< kg
    real(wp) :: inertia(3) = 0.0_wp    !< kg m^2, principal moments about body x, y, z (Eq. 12)
  end type spheroid_t

contains

  !> Spheroid from a shape name, volume-equivalent radius (m) and density (kg/m^3).
  !> aspect_ratio: for 'needle' and 'disk' the ratio of the long to the short semi-axis (>= 1,
  !> default 5: needle a/b = aspect_ratio, disk a/b = 1/aspect_ratio); for 'spheroid' a/b itself
  !> (> 0, required); for 'sphere' it must be absent or 1.
  function make_spheroid(shape, radius, density, aspect_ratio) result(s)
    character(len=*), intent(in) :: shape
    real(wp), intent(in) :: radius, density
    real(wp), intent(in), optional :: aspect_ratio
    type(spheroid_t) :: s
    real(wp) :: ratio_a_over_b
    character(len=32) :: text

    if (.not. (radius > 0.0_wp)) then
      write(text, '(es12.5)') radius
      call fatal('spheroid: radius = '//trim(text)//' m; it must be > 0')
    end if
    if (.not. (density > 0.0_wp)) then
      write(text, '(es12.5)') density
      call fatal('spheroid: density = '//trim(text)//' kg/m^3; it must be > 0')
    end if
    text = ''
    if (present(aspect_ratio)) write(text, '(es12.5)') aspect_ratio

    select case (trim(shape))
    case ('sphere')
      if (present(aspect_ratio)) then
        if (aspect_ratio /= 1.0_wp) call fatal('spheroid: shape ''sphere'' with aspect_ratio = '// &
                                               trim(text)//'; a sphere has aspect ratio 1')
      end if
      ratio_a_over_b = 1.0_wp
    case ('needle', 'disk')
      ratio_a_over_b = default_aspect_ratio
      if (present(aspect_ratio)) then
        if (.not. (aspect_ratio >= 1.0_wp)) call fatal('spheroid: shape '''//trim(shape)// &
          ''' with aspect_ratio = '//trim(text)//'; it is long/short semi-axes and must be >= 1 '// &
          '(use shape ''spheroid'' to give a/b directly)')
        ratio_a_over_b = aspect_ratio
      end if
      if (trim(shape) == 'disk') ratio_a_over_b = 1.0_wp / ratio_a_over_b
    case ('spheroid')
      if (.not. present(aspect_ratio)) call fatal('spheroid: shape ''spheroid'' needs aspect_ratio = a/b')
      if (.not. (aspect_ratio > 0.0_wp)) call fatal('spheroid: shape ''spheroid'' with aspect_ratio = '// &
                                                    trim(text)//'; a/b must be > 0')
      ratio_a_over_b = aspect_ratio
    case default
      call fatal('spheroid: unknown shape '''//trim(shape)//'''; allowed: sphere, needle, disk, spheroid')
    end select

    s%shape = shape
    s%radius = radius
    s%density = density
    s%aspect_ratio = ratio_a_over_b
    ! a b^2 = r^3 with a = (a/b) b  =>  b = r (a/b)^(-1/3), a = r (a/b)^(2/3).
    s%b = radius * ratio_a_over_b**(-1.0_wp/3.0_wp)
    s%a = radius * ratio_a_over_b**(2.0_wp/3.0_wp)
    if (trim(shape) == 'sphere') then
      s%a = radius
      s%b = radius
    end if
    s%volume = 4.0_wp / 3.0_wp * pi * radius**3
    s%mass = density * s%volume
    ! Eq. 12 of the paper with c = b.
    s%inertia(1) = 0.4_wp * s%mass * s%b**2
    s%inertia(2) = 0.2_wp * s%mass * (s%a**2 + s%b**2)
    s%inertia(3) = s%inertia(2)
  end function make_spheroid

  !> Surface point (body frame) at parametric angles (theta, phi).
  pure function surface_point(s, theta, phi) result(p)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: theta, phi
    real(wp) :: p(3)
    p = [s%a * cos(phi), s%b * sin(phi) * cos(theta), s%b * sin(phi) * sin(theta)]
  end function surface_point

  !> Outward unit normal (body frame) at (theta, phi): proportional to (x/a^2, y/b^2, z/b^2).
  pure function surface_normal(s, theta, phi) result(n)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: theta, phi
    real(wp) :: n(3)
    n = [cos(phi) / s%a, sin(phi) * cos(theta) / s%b, sin(phi) * sin(theta) / s%b]
    n = n / norm2(n)
  end function surface_normal

  !> Principal curvatures (1/m, positive: the surface is convex) at parametric angle phi, with
  !> D = a^2 sin^2(phi) + b^2 cos^2(phi) (docs/physics.md section 1):
  !> meridional kappa_m = a b / D^(3/2), parallel kappa_p = a / (b sqrt(D)).
  pure subroutine principal_curvatures(s, phi, kappa_meridional, kappa_parallel)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: phi
    real(wp), intent(out) :: kappa_meridional, kappa_parallel
    real(wp) :: d
    d = (s%a * sin(phi))**2 + (s%b * cos(phi))**2
    kappa_meridional = s%a * s%b / d**1.5_wp
    kappa_parallel = s%a / (s%b * sqrt(d))
  end subroutine principal_curvatures

  !> Unit principal directions (body frame) at (theta, phi): the meridian tangent (direction of
  !> increasing phi) and the parallel tangent (0, -sin theta, cos theta). (meridian, parallel,
  !> outward normal) is right-handed for every phi; both are defined at the poles, where any
  !> tangent is principal (umbilic) and theta selects one.
  pure subroutine principal_directions(s, theta, phi, meridian_tangent, parallel_tangent)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: theta, phi
    real(wp), intent(out) :: meridian_tangent(3), parallel_tangent(3)
    meridian_tangent = [-s%a * sin(phi), s%b * cos(phi) * cos(theta), s%b * cos(phi) * sin(theta)]
    meridian_tangent = meridian_tangent / norm2(meridian_tangent)
    parallel_tangent = [0.0_wp, -sin(theta), cos(theta)]
  end subroutine principal_directions

  !> Inverse of surface_point: (theta, phi) of a body-frame point on (or near: the point is taken
  !> along the scaled radius) the surface. theta in [0, pi], phi in (-pi, pi]. On the axis
  !> (the poles) theta = 0 and phi = 0 or pi. z < 0 (and z = 0, y < 0) is reached with sin(phi) < 0.
  pure subroutine surface_angles(s, p, theta, phi)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: p(3)
    real(wp), intent(out) :: theta, phi
    real(wp) :: rho, sine_phi
    rho = sqrt(p(2)**2 + p(3)**2)
    if (rho == 0.0_wp) then
      theta = 0.0_wp
      sine_phi = 0.0_wp
    else if (p(3) < 0.0_wp .or. (p(3) == 0.0_wp .and. p(2) < 0.0_wp)) then
      ! abs() also turns a signed zero into +0, so theta never comes out as -pi or -0.
      theta = atan2(abs(p(3)), -p(2))
      sine_phi = -rho / s%b
    else
      theta = atan2(abs(p(3)), p(2))
      sine_phi = rho / s%b
    end if
    phi = atan2(sine_phi, p(1) / s%a)
  end subroutine surface_angles

  !> Implicit function F(p) = x^2/a^2 + (y^2 + z^2)/b^2 - 1 (< 0 inside, 0 on the surface).
  pure function implicit_function(s, p) result(f)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: p(3)
    real(wp) :: f
    f = (p(1) / s%a)**2 + (p(2)**2 + p(3)**2) / s%b**2 - 1.0_wp
  end function implicit_function

  pure function implicit_gradient(s, p) result(g)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: p(3)
    real(wp) :: g(3)
    g = 2.0_wp * [p(1) / s%a**2, p(2) / s%b**2, p(3) / s%b**2]
  end function implicit_gradient

  !> Outward unit normal at a body-frame surface point: the normalised implicit gradient.
  pure function normal_at_point(s, p) result(n)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: p(3)
    real(wp) :: n(3)
    n = [p(1) / s%a**2, p(2) / s%b**2, p(3) / s%b**2]
    n = n / norm2(n)
  end function normal_at_point

  !> The surface point whose outward normal is m (body frame, any non-zero length):
  !> y = S^2 m / sqrt(m^T S^2 m), S = diag(a, b, b) (docs/physics.md section 6). It is also the support
  !> point: the point of the spheroid furthest along m.
  pure function support_point(s, m) result(y)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: m(3)
    real(wp) :: y(3)
    y = [s%a**2 * m(1), s%b**2 * m(2), s%b**2 * m(3)]
    y = y / sqrt(dot_product(m, y))
  end function support_point

  !> Support function h(m) = max over the spheroid of p.m = sqrt(m^T S^2 m) (body frame, unit m).
  pure function support_value(s, m) result(h)
    type(spheroid_t), intent(in) :: s
    real(wp), intent(in) :: m(3)
    real(wp) :: h
    h = sqrt((s%a * m(1))**2 + (s%b * m(2))**2 + (s%b * m(3))**2)
  end function support_value

  !> Analytic surface area (m^2). Prolate (a > b): 2 pi b^2 (1 + a asin(e)/(b e)), e^2 = 1 - b^2/a^2;
  !> oblate (a < b): 2 pi b^2 (1 + (1 - e^2) atanh(e)/e), e^2 = 1 - a^2/b^2. Near e = 0 the series
  !> asin(e)/e = 1 + e^2/6 + 3e^4/40 and atanh(e)/e = 1 + e^2/3 + e^4/5 avoid the cancellation.
  pure function surface_area(s) result(area)
    type(spheroid_t), intent(in) :: s
    real(wp) :: area, e, ratio
    if (s%a >= s%b) then
      e = sqrt(max(0.0_wp, 1.0_wp - (s%b / s%a)**2))
      if (e < 1.0e-3_wp) then
        ratio = 1.0_wp + e**2 / 6.0_wp + 3.0_wp * e**4 / 40.0_wp
      else
        ratio = asin(e) / e
      end if
      area = 2.0_wp * pi * s%b**2 * (1.0_wp + s%a / s%b * ratio)
    else
      e = sqrt(max(0.0_wp, 1.0_wp - (s%a / s%b)**2))
      if (e < 1.0e-3_wp) then
        ratio = 1.0_wp + e**2 / 3.0_wp + e**4 / 5.0_wp
      else
        ratio = atanh(e) / e
      end if
      area = 2.0_wp * pi * s%b**2 * (1.0_wp + (1.0_wp - e**2) * ratio)
    end if
  end function surface_area

end module spheroid
