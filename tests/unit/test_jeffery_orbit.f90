! checks: 18
!> Jeffery orbits (physics.md section 5): the rotation integrator of rigid_body / quaternion driven by
!> the imposed torque-free kinematics of a spheroid in Stokes flow, for aspect ratio lambda = 5
!> (prolate) and 1/5 (oblate), against Jeffery's exact solution.
!>
!> Simple shear u = (shear_rate y, 0, 0): vorticity w_f = curl u = (0, 0, -shear_rate), strain rate
!> E = (grad u + grad u^T)/2, E p = shear_rate/2 (p_y, p_x, 0). A torque-free axisymmetric spheroid with
!> unit symmetry axis p rotates with (Jeffery 1922, Proc. R. Soc. Lond. A 102, 161-179; in vector
!> form with Bretherton's constant, Bretherton 1962, J. Fluid Mech. 14, 284-304)
!>     omega = w_f / 2 + B p x (E p),     B = (lambda^2 - 1) / (lambda^2 + 1),
!> so that dp/dt = omega x p = W p + B (E p - (p.E.p) p) with W the rotation-rate tensor.
!> With p = (sin theta cos phi, sin theta sin phi, cos theta) (phi from the flow direction, theta from
!> the vorticity axis) this gives dphi/dt = -shear_rate (cos^2 phi + lambda^2 sin^2 phi) / (lambda^2 + 1),
!> independent of theta, solved by tan phi = -(1/lambda) tan(shear_rate t / (lambda + 1/lambda)) for
!> phi(0) = 0: the period is shear_rate T = 2 pi (lambda + 1/lambda) = 32.67 for lambda = 5 or 1/5.
!> And d ln tan theta/dt = B shear_rate sin phi cos phi = -1/2 d ln(cos^2 phi + lambda^2 sin^2 phi)/dt, so
!> the orbit constant C = tan theta sqrt(cos^2 phi + lambda^2 sin^2 phi) is conserved.
!>
!> Integrators, both through rigid_body_step (whose quaternion update is quaternion_advance, the exact
!> exponential map for an angular velocity held over the step):
!>  - 'euler' (the paper's scheme): omega from the orientation at the start of the step; order 1.
!>  - 'midpoint': a half step gives the orientation at t + dt/2, whose omega (lab frame, converted with
!>    the start-of-step orientation) is held over the whole step: the explicit midpoint rule on the
!>    rotation group (Munthe-Kaas 1998, BIT 38, 92-111, RKMK of order 2).
program test_jeffery_orbit
  use agglo_kinds, only: wp
  use physical_constants, only: pi, two_pi
  use vector_algebra, only: cross
  use quaternion, only: quaternion_product, quaternion_from_axis_angle, symmetry_axis, quaternion_norm
  use rigid_body, only: rigid_body_t, rigid_body_init, rigid_body_step, set_angular_velocity_lab, integrator_euler
  use test_framework, only: test_start, test_finish, check_close, check_below
  implicit none
  real(wp), parameter :: shear_rate = 2.0_wp          !< 1/s
  real(wp), parameter :: initial_theta = 1.0_wp       !< rad, symmetry axis from the vorticity axis at t = 0
  real(wp), parameter :: lambdas(2) = [5.0_wp, 0.2_wp]
  integer, parameter :: euler = 1, midpoint = 2
  character(len=8), parameter :: scheme_names(2) = [character(len=8) :: 'euler', 'midpoint']
  character(len=8), parameter :: lambda_names(2) = [character(len=8) :: '5', '1/5']
  real(wp) :: period, axis_error(3, 2), drift(3, 2), norm_error, order, exact_period
  character(len=200) :: line
  integer :: l, scheme, level

  call test_start('jeffery_orbit')
  do l = 1, 2
    exact_period = two_pi * (lambdas(l) + 1.0_wp / lambdas(l)) / shear_rate
    ! Three orbits with the midpoint rule at 8000 steps per period.
    call integrate(lambdas(l), midpoint, 8000, 3, period, axis_error(1, midpoint), drift(1, midpoint), norm_error)
    write(line, '(a,a,a,f12.8,a,f12.8,a,es10.3,a,es10.3)') 'lambda ', trim(lambda_names(l)), &
        ': shear_rate T = ', shear_rate * period, ' (exact ', shear_rate * exact_period, '), orbit constant drift ', &
        drift(1, midpoint), ', |p - p_exact| ', axis_error(1, midpoint)
    write(*, '(a)') trim(line)
    call check_close(shear_rate * period, 2.0_wp * pi * (lambdas(l) + 1.0_wp / lambdas(l)), 1.0e-4_wp, &
                     'period_lambda_'//trim(lambda_names(l)))
    call check_below(drift(1, midpoint), 1.0e-4_wp, 'orbit_constant_conserved_lambda_'//trim(lambda_names(l)))
    call check_below(axis_error(1, midpoint), 1.0e-4_wp, 'axis_follows_exact_orbit_lambda_'//trim(lambda_names(l)))
    call check_below(norm_error, 1.0e-13_wp, 'unit_quaternion_lambda_'//trim(lambda_names(l)))

    ! Convergence: one period at 1000, 2000, 4000 steps; orders between the coarsest and the finest
    ! (design orders 1 and 2, within 0.1).
    do scheme = euler, midpoint
      do level = 1, 3
        call integrate(lambdas(l), scheme, 1000 * 2**(level - 1), 1, period, axis_error(level, scheme), &
                       drift(level, scheme), norm_error)
        write(line, '(a,a,a,a,a,i0,a,es10.3,a,es10.3,a,es10.3)') 'lambda ', trim(lambda_names(l)), ' ', &
            trim(scheme_names(scheme)), ' steps/period ', 1000 * 2**(level - 1), ': |p - p_exact| ', &
            axis_error(level, scheme), '  orbit constant drift ', drift(level, scheme), &
            '  period error ', abs(period - exact_period) / exact_period
        write(*, '(a)') trim(line)
      end do
      if (scheme == euler) call check_close(period, exact_period, 1.0e-4_wp, 'euler_period_4000_steps_lambda_'// &
                                            trim(lambda_names(l)))
      order = log(axis_error(1, scheme) / axis_error(3, scheme)) / log(4.0_wp)
      call check_close(order, real(scheme, wp), 0.1_wp / scheme, trim(scheme_names(scheme))//'_order_axis_lambda_'// &
                       trim(lambda_names(l)))
      order = log(drift(1, scheme) / drift(3, scheme)) / log(4.0_wp)
      call check_above_order(order, real(scheme, wp), trim(scheme_names(scheme))//'_order_orbit_constant_lambda_'// &
                             trim(lambda_names(l)))
    end do
  end do
  call test_finish()

contains

  !> Jeffery's angular velocity (lab frame) of a spheroid with symmetry axis p in the shear above.
  pure function jeffery_angular_velocity(p, lambda) result(omega)
    real(wp), intent(in) :: p(3), lambda
    real(wp) :: omega(3), strain_p(3), bretherton
    bretherton = (lambda**2 - 1.0_wp) / (lambda**2 + 1.0_wp)
    strain_p = 0.5_wp * shear_rate * [p(2), p(1), 0.0_wp]
    omega = 0.5_wp * [0.0_wp, 0.0_wp, -shear_rate] + bretherton * cross(p, strain_p)
  end function jeffery_angular_velocity

  !> Jeffery's exact symmetry axis at time t for phi(0) = 0 and orbit constant c.
  pure function exact_axis(t, lambda, c) result(p)
    real(wp), intent(in) :: t, lambda, c
    real(wp) :: p(3), psi, cos_phi, sin_phi, scale, theta
    psi = shear_rate * t / (lambda + 1.0_wp / lambda)
    scale = sqrt((lambda * cos(psi))**2 + sin(psi)**2)
    cos_phi = lambda * cos(psi) / scale
    sin_phi = -sin(psi) / scale
    theta = atan(c / sqrt(cos_phi**2 + (lambda * sin_phi)**2))
    p = [sin(theta) * cos_phi, sin(theta) * sin_phi, cos(theta)]
  end function exact_axis

  !> Orbit constant C = tan theta sqrt(cos^2 phi + lambda^2 sin^2 phi) of the axis p.
  pure real(wp) function orbit_constant(p, lambda)
    real(wp), intent(in) :: p(3), lambda
    real(wp) :: in_plane
    in_plane = norm2(p(1:2))
    orbit_constant = in_plane / p(3) * sqrt((p(1) / in_plane)**2 + (lambda * p(2) / in_plane)**2)
  end function orbit_constant

  !> Integrate periods Jeffery periods (and a quarter more, so that the last crossing is seen whether
  !> the numerical phase lags or leads) at steps_per_period steps each. Returns the measured period
  !> (the time the unwrapped azimuth phi passes -2 pi periods, divided by periods; the crossing is
  !> interpolated linearly: at phi = 0 mod pi, d^2 phi/dt^2 = 0, so that error is O(dt^3)), and over
  !> the whole run the largest |p - p_exact|, |C - C0| / C0 and ||q| - 1|.
  subroutine integrate(lambda, scheme, steps_per_period, periods, period, max_axis_error, max_drift, max_norm_error)
    real(wp), intent(in) :: lambda
    integer, intent(in) :: scheme, steps_per_period, periods
    real(wp), intent(out) :: period, max_axis_error, max_drift, max_norm_error
    real(wp), parameter :: zero(3) = 0.0_wp
    type(rigid_body_t) :: body, half
    real(wp) :: dt, t, q0(4), p(3), c0, phi, phi_old, step_angle, target, crossing_time, previous_p(3)
    integer :: n, crossings
    dt = two_pi * (lambda + 1.0_wp / lambda) / shear_rate / steps_per_period
    ! Axis at (sin theta0, 0, cos theta0) (rotation of body x about lab y by theta0 - pi/2), with an
    ! arbitrary initial spin about the axis itself (it must not change the axis motion).
    q0 = quaternion_product(quaternion_from_axis_angle([0.0_wp, 1.0_wp, 0.0_wp], initial_theta - 0.5_wp * pi), &
                            quaternion_from_axis_angle([1.0_wp, 0.0_wp, 0.0_wp], 0.7_wp))
    call rigid_body_init(body, 1.0_wp, [1.0_wp, 1.0_wp, 1.0_wp], zero, q0)
    p = symmetry_axis(body%quaternion)
    c0 = orbit_constant(p, lambda)
    t = 0.0_wp
    phi = 0.0_wp
    crossings = 0
    crossing_time = 0.0_wp
    max_axis_error = norm2(p - exact_axis(t, lambda, c0))
    max_drift = 0.0_wp
    max_norm_error = 0.0_wp
    do n = 1, steps_per_period * periods + steps_per_period / 4
      previous_p = p
      select case (scheme)
      case (euler)
        call set_angular_velocity_lab(body, jeffery_angular_velocity(p, lambda))
      case (midpoint)
        half = body
        call set_angular_velocity_lab(half, jeffery_angular_velocity(p, lambda))
        call rigid_body_step(half, zero, zero, 0.5_wp * dt, integrator_euler)
        call set_angular_velocity_lab(body, jeffery_angular_velocity(symmetry_axis(half%quaternion), lambda))
      end select
      call rigid_body_step(body, zero, zero, dt, integrator_euler)
      t = n * dt
      p = symmetry_axis(body%quaternion)
      max_axis_error = max(max_axis_error, norm2(p - exact_axis(t, lambda, c0)))
      max_drift = max(max_drift, abs(orbit_constant(p, lambda) - c0) / c0)
      max_norm_error = max(max_norm_error, abs(quaternion_norm(body%quaternion) - 1.0_wp))
      ! Unwrapped azimuth: add the signed angle between the projections of consecutive axes.
      phi_old = phi
      step_angle = atan2(previous_p(1) * p(2) - previous_p(2) * p(1), previous_p(1) * p(1) + previous_p(2) * p(2))
      phi = phi + step_angle
      target = -two_pi * (crossings + 1)
      if (phi_old > target .and. phi <= target) then
        crossings = crossings + 1
        if (crossings == periods) crossing_time = t - dt + dt * (phi_old - target) / (phi_old - phi)
      end if
    end do
    period = huge(1.0_wp)
    if (crossings >= periods) period = crossing_time / periods
  end subroutine integrate

  !> A measured convergence order at least the design order minus 0.1 (superconvergence allowed).
  subroutine check_above_order(order, design, name)
    real(wp), intent(in) :: order, design
    character(len=*), intent(in) :: name
    call check_close(min(order, design), design, 0.1_wp / design, name)
  end subroutine check_above_order
end program test_jeffery_orbit
