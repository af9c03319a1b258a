! checks: 31
!> Unit tests of stokes_resistance: Oberbeck/Perrin coefficients against docs/physics.md section 4 and
!> the analytic exponential decay of a lone spheroid's translation and rotation in quiescent fluid.
program test_stokes_resistance
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_setup, spheroid_resistance_coefficients, &
                               stokes_loads_lab
  use rigid_body, only: rigid_body_t, rigid_body_init, rigid_body_step, angular_velocity_lab, integrator_euler, &
                        integrator_verlet
  use quaternion, only: rotation_matrix, quaternion_from_axis_angle, rotate_to_lab
  use test_framework, only: test_start, test_finish, check_close, check_below
  implicit none
  real(wp), parameter :: r = 50.0e-6_wp, density = 2710.0_wp, mu = 997.0_wp * 1.0e-6_wp
  real(wp) :: c(4), needle(4), disk(4), lambda, below(4), above(4), a, b

  call test_start('stokes_resistance')

  ! docs/physics.md section 4 (Oberbeck/Perrin, normalised by 6 pi mu r U and 8 pi mu r^3 Omega):
  needle = [1.0438_wp, 1.3865_wp, 0.7061_wp, 4.6405_wp]
  disk = [1.4731_wp, 1.1279_wp, 2.6718_wp, 2.2398_wp]
  lambda = 5.0_wp
  c = spheroid_resistance_coefficients(r * lambda**(2.0_wp / 3.0_wp), r * lambda**(-1.0_wp / 3.0_wp))
  call check_coefficients(c, needle, 'needle5')
  lambda = 0.2_wp
  c = spheroid_resistance_coefficients(r * lambda**(2.0_wp / 3.0_wp), r * lambda**(-1.0_wp / 3.0_wp))
  call check_coefficients(c, disk, 'disk5')
  c = spheroid_resistance_coefficients(r, r)
  call check_coefficients(c, [1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp], 'sphere')
  ! Aspect ratio 1.0001 (series branch): within 1e-4 of the sphere (the first-order shift is ~1e-5).
  lambda = 1.0001_wp
  c = spheroid_resistance_coefficients(r * lambda**(2.0_wp / 3.0_wp), r * lambda**(-1.0_wp / 3.0_wp))
  call check_coefficients(c, [1.0_wp, 1.0_wp, 1.0_wp, 1.0_wp], 'near_sphere')
  ! Series and closed form agree across the switch at |b^2 - a^2| = 0.1 a^2 (continuity to 1e-12).
  a = r
  b = r * sqrt(1.0999999_wp)
  below = spheroid_resistance_coefficients(a, b)
  b = r * sqrt(1.1000001_wp)
  above = spheroid_resistance_coefficients(a, b)
  call check_below(maxval(abs(above - below)), 1.0e-6_wp, 'series_closed_form_continuous')
  ! Aspect ratios 20 and 1/20: finite and ordered (needle: axial drag < transverse drag).
  lambda = 20.0_wp
  c = spheroid_resistance_coefficients(r * lambda**(2.0_wp / 3.0_wp), r * lambda**(-1.0_wp / 3.0_wp))
  call check_below(c(1) - c(2), 0.0_wp, 'needle20_axial_below_transverse')
  lambda = 0.05_wp
  c = spheroid_resistance_coefficients(r * lambda**(2.0_wp / 3.0_wp), r * lambda**(-1.0_wp / 3.0_wp))
  call check_below(c(2) - c(1), 0.0_wp, 'disk20_transverse_below_axial')

  call check_decay(5.0_wp, 'needle')
  call check_decay(0.2_wp, 'disk')

  call test_finish()

contains

  subroutine check_coefficients(actual, expected, name)
    real(wp), intent(in) :: actual(4), expected(4)
    character(len=*), intent(in) :: name
    ! The reference values carry 5 significant digits: agreement to 1e-4 relative.
    call check_close(actual(1), expected(1), 1.0e-4_wp, name//'_force_axial')
    call check_close(actual(2), expected(2), 1.0e-4_wp, name//'_force_transverse')
    call check_close(actual(3), expected(3), 1.0e-4_wp, name//'_torque_axial')
    call check_close(actual(4), expected(4), 1.0e-4_wp, name//'_torque_transverse')
  end subroutine check_coefficients

  !> A lone spheroid (symmetry axis tilted in the lab) with velocity along and across its axis, then
  !> spinning about and across it: m dU/dt = -zeta U gives U = U0 exp(-t zeta / m) per principal
  !> direction, I dw/dt = -zeta_r w likewise (no gyroscopic term for rotation about one principal
  !> axis). Integrated with dt = tau/2000 over one tau: the Euler/frozen-load error is ~ dt/(2 tau).
  subroutine check_decay(aspect_ratio, name)
    real(wp), intent(in) :: aspect_ratio
    character(len=*), intent(in) :: name
    type(stokes_resistance_t) :: res
    type(rigid_body_t) :: body
    real(wp) :: a, b, mass, inertia(3), q(4), axis(3), transverse(3), force(3), torque(3), tau, dt, u(3), w(3)
    integer :: direction, k, nsteps
    character(len=12), parameter :: labels(2) = [character(len=12) :: 'axial', 'transverse']
    a = r * aspect_ratio**(2.0_wp / 3.0_wp)
    b = r * aspect_ratio**(-1.0_wp / 3.0_wp)
    mass = density * 4.0_wp / 3.0_wp * pi * a * b * b
    inertia = [0.4_wp * mass * b * b, 0.2_wp * mass * (a * a + b * b), 0.2_wp * mass * (a * a + b * b)]
    call stokes_resistance_setup(res, a, b, mu)
    q = quaternion_from_axis_angle([1.0_wp, 2.0_wp, -0.5_wp] / norm2([1.0_wp, 2.0_wp, -0.5_wp]), 0.7_wp)
    axis = rotate_to_lab(q, [1.0_wp, 0.0_wp, 0.0_wp])
    transverse = rotate_to_lab(q, [0.0_wp, 0.0_wp, 1.0_wp])
    nsteps = 2000
    do direction = 1, 2
      ! translation
      tau = mass / res%translational(direction)
      dt = tau / nsteps
      u = merge(axis, transverse, direction == 1) * 1.0e-3_wp
      call rigid_body_init(body, mass, inertia, [0.0_wp, 0.0_wp, 0.0_wp], q, velocity=u)
      do k = 1, nsteps
        call stokes_loads_lab(res, rotation_matrix(body%quaternion), body%velocity, angular_velocity_lab(body), force, torque)
        call rigid_body_step(body, force, torque, dt, integrator_verlet)
      end do
      call check_close(dot_product(body%velocity, u) / dot_product(u, u), exp(-1.0_wp), 1.0e-3_wp, &
                       name//'_translation_decay_'//trim(labels(direction)))
      call check_below(norm2(body%velocity - dot_product(body%velocity, u) / dot_product(u, u) * u), &
                       1.0e-12_wp * norm2(u), name//'_translation_stays_principal_'//trim(labels(direction)))
      ! rotation
      tau = inertia(direction) / res%rotational(direction)
      dt = tau / nsteps
      w = merge(axis, transverse, direction == 1) * 10.0_wp
      call rigid_body_init(body, mass, inertia, [0.0_wp, 0.0_wp, 0.0_wp], q, angular_velocity=w)
      do k = 1, nsteps
        call stokes_loads_lab(res, rotation_matrix(body%quaternion), body%velocity, angular_velocity_lab(body), force, torque)
        call rigid_body_step(body, force, torque, dt, integrator_euler)
      end do
      call check_close(norm2(angular_velocity_lab(body)) / norm2(w), exp(-1.0_wp), 1.0e-3_wp, &
                       name//'_rotation_decay_'//trim(labels(direction)))
    end do
  end subroutine check_decay
end program test_stokes_resistance
