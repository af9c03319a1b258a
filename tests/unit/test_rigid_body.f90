! checks: 17
!> Unit tests of rigid_body: torque-free symmetric top against its exact solution (precession
!> rate (I3 - I1) w3 / I1 in the body frame, Landau & Lifshitz, Mechanics, sec. 33), measured
!> convergence orders of both integrators, energy and angular-momentum conservation, constant
!> force, sub-steps, and the quaternion norm over 1e6 steps.
program test_rigid_body
  use agglo_kinds, only: wp
  use rigid_body, only: rigid_body_t, rigid_body_init, rigid_body_step, kinetic_energy, &
                        angular_momentum, integrator_euler, integrator_verlet, &
                        rigid_body_kick, rigid_body_drift
  use quaternion, only: quaternion_product, quaternion_from_axis_angle
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  ! Symmetric top (prolate, like a needle): I3 = I_x about the symmetry axis, I1 = I_y = I_z.
  real(wp), parameter :: i3 = 0.4_wp, i1 = 1.0_wp, w3 = 2.0_wp, w_perp = 1.0_wp, total_time = 10.0_wp
  real(wp) :: q0(4), errors_w(3, 2), errors_q(3, 2), errors_e(3, 2), errors_l(3, 2), order
  real(wp) :: rate, energy0, l0(3)
  type(rigid_body_t) :: body
  integer :: s, k, scheme
  character(len=8), parameter :: names(2) = [character(len=8) :: 'euler', 'verlet']
  character(len=160) :: line

  call test_start('rigid_body')
  q0 = quaternion_from_axis_angle([0.3_wp, -0.4_wp, 0.866_wp] / norm2([0.3_wp, -0.4_wp, 0.866_wp]), 1.1_wp)

  do scheme = 1, 2
    do s = 1, 3
      call run_top(scheme, 1000 * 2**(s - 1), errors_w(s, scheme), errors_q(s, scheme), errors_e(s, scheme), &
                   errors_l(s, scheme))
    end do
    do s = 1, 3
      write(line, '(a,a,a,i0,a,4es11.3)') 'top ', trim(names(scheme)), ' steps ', 1000 * 2**(s - 1), &
          ': |dw|, |dq|, dE/E, d|L|/|L| =', errors_w(s, scheme), errors_q(s, scheme), errors_e(s, scheme), errors_l(s, scheme)
      write(*, '(a)') trim(line)
    end do
  end do
  ! Measured orders between dt and dt/4 (expected 1 for Euler, 2 for the splitting).
  order = log(errors_w(1, 1) / errors_w(3, 1)) / log(4.0_wp)
  call check_close(order, 1.0_wp, 0.1_wp, 'euler_order_angular_velocity')
  order = log(errors_q(1, 1) / errors_q(3, 1)) / log(4.0_wp)
  call check_close(order, 1.0_wp, 0.1_wp, 'euler_order_orientation')
  order = log(errors_e(1, 1) / errors_e(3, 1)) / log(4.0_wp)
  call check_close(order, 1.0_wp, 0.1_wp, 'euler_order_energy')
  order = log(errors_w(1, 2) / errors_w(3, 2)) / log(4.0_wp)
  call check_close(order, 2.0_wp, 0.1_wp, 'verlet_order_angular_velocity')
  order = log(errors_q(1, 2) / errors_q(3, 2)) / log(4.0_wp)
  call check_close(order, 2.0_wp, 0.1_wp, 'verlet_order_orientation')
  order = log(errors_e(1, 2) / errors_e(3, 2)) / log(4.0_wp)
  call check_close(order, 2.0_wp, 0.1_wp, 'verlet_order_energy')
  ! The splitting's sub-rotations keep the lab angular momentum exactly (round-off only).
  call check_below(maxval(errors_l(:, 2)), 1.0e-13_wp, 'verlet_angular_momentum_round_off')
  ! At 4000 steps over 10 s (dt = 2.5e-3 s) the precession phase is accurate:
  call check_below(errors_w(3, 2), 1.0e-4_wp, 'verlet_top_angular_velocity_4000_steps')
  call check_below(errors_w(3, 1), 5.0e-2_wp, 'euler_top_angular_velocity_4000_steps')

  ! Asymmetric free body (I = 1, 2, 3), rotation near the unstable middle axis: over 2e4 steps the
  ! splitting's energy error stays bounded (no drift) and |L| is kept.
  call rigid_body_init(body, 1.0_wp, [1.0_wp, 2.0_wp, 3.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], q0)
  body%angular_velocity_body = [0.01_wp, 1.0_wp, 0.02_wp]
  energy0 = kinetic_energy(body)
  l0 = angular_momentum(body)
  rate = 0.0_wp
  do k = 1, 20000
    call rigid_body_step(body, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], 5.0e-3_wp, integrator_verlet)
    rate = max(rate, abs(kinetic_energy(body) - energy0) / energy0)
  end do
  call check_below(rate, 1.0e-4_wp, 'asymmetric_body_energy_bounded')
  call check_below(norm2(angular_momentum(body) - l0) / norm2(l0), 1.0e-12_wp, 'asymmetric_body_angular_momentum')

  ! Constant force and torque-free: the splitting is exact for x(t) = x0 + U0 t + F t^2 / (2m).
  call rigid_body_init(body, 2.0_wp, [1.0_wp, 1.0_wp, 1.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[0.0_wp, 1.0_wp, 0.0_wp])
  do k = 1, 100
    call rigid_body_step(body, [0.0_wp, 0.0_wp, -4.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], 0.01_wp, integrator_verlet)
  end do
  call check_below(norm2(body%position - [1.0_wp, 1.0_wp, -1.0_wp]), 1.0e-13_wp, 'verlet_constant_force_exact')
  ! Steps of another length under the same load: 80 steps of 0.0125 give the same exact trajectory.
  call rigid_body_init(body, 2.0_wp, [1.0_wp, 1.0_wp, 1.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[0.0_wp, 1.0_wp, 0.0_wp])
  do k = 1, 80
    call rigid_body_step(body, [0.0_wp, 0.0_wp, -4.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], 0.0125_wp, integrator_verlet)
  end do
  call check_below(norm2(body%position - [1.0_wp, 1.0_wp, -1.0_wp]), 1.0e-13_wp, 'verlet_constant_force_exact_other_dt')
  ! Euler (paper): x_{n+1} = x_n + U_n dt is first order: error F T dt / (2m) = 4 * 1 * 0.01 / 4 = 0.01.
  call rigid_body_init(body, 2.0_wp, [1.0_wp, 1.0_wp, 1.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[0.0_wp, 1.0_wp, 0.0_wp])
  do k = 1, 100
    call rigid_body_step(body, [0.0_wp, 0.0_wp, -4.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], 0.01_wp, integrator_euler)
  end do
  call check_close(body%position(3), -1.0_wp + 0.01_wp, 1.0e-12_wp, 'euler_constant_force_first_order')

  ! Kick/drift primitives compose to rigid_body_step.
  call rigid_body_init(body, 1.0_wp, [i3, i1, i1], [0.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[1.0_wp, 0.0_wp, 0.0_wp])
  body%angular_velocity_body = [w3, w_perp, 0.0_wp]
  call rigid_body_kick(body, [1.0_wp, 2.0_wp, 3.0_wp], [0.1_wp, 0.0_wp, 0.2_wp], 0.05_wp)
  call rigid_body_drift(body, 0.1_wp)
  call rigid_body_kick(body, [1.0_wp, 2.0_wp, 3.0_wp], [0.1_wp, 0.0_wp, 0.2_wp], 0.05_wp)
  l0 = body%angular_velocity_body
  call rigid_body_init(body, 1.0_wp, [i3, i1, i1], [0.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[1.0_wp, 0.0_wp, 0.0_wp])
  body%angular_velocity_body = [w3, w_perp, 0.0_wp]
  call rigid_body_step(body, [1.0_wp, 2.0_wp, 3.0_wp], [0.1_wp, 0.0_wp, 0.2_wp], 0.1_wp, integrator_verlet)
  ! Same operations in the same order, but rigid_body_step's inlined copies may be contracted into
  ! fused multiply-adds differently from the separate calls (-march=native): agreement to rounding
  ! (1e-14 relative, about 45 ulp over some 100 operations), not bit for bit; a different splitting differs at O(h).
  call check_below(norm2(body%angular_velocity_body - l0), 1.0e-14_wp * norm2(l0), 'kick_drift_kick_is_step')

  ! Quaternion norm after 1e6 Euler steps of a spinning body: |q| - 1 <= 1e-12.
  call rigid_body_init(body, 1.0_wp, [i3, i1, i1], [0.0_wp, 0.0_wp, 0.0_wp], q0)
  body%angular_velocity_body = [w3, w_perp, 0.3_wp]
  do k = 1, 1000000
    call rigid_body_step(body, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], 1.0e-5_wp, integrator_euler)
  end do
  call check_below(abs(norm2(body%quaternion) - 1.0_wp), 1.0e-12_wp, 'quaternion_norm_1e6_steps')
  call check(all(body%angular_velocity_body == body%angular_velocity_body), 'no_nan_after_1e6_steps')

  call test_finish()

contains

  !> Torque-free symmetric top from omega_body(0) = (w3, w_perp, 0) over total_time in n steps.
  !> Exact solution: omega_body = (w3, w_perp cos(W t), w_perp sin(W t)), W = (I3 - I1) w3 / I1;
  !> q(t) = qL(t) (x) q0 (x) q3(t), qL = rotation by |L| t / I1 about the fixed lab L,
  !> q3 = rotation by -W t about the body symmetry axis (omega_body = L_body / I1 - W e_x).
  subroutine run_top(scheme, n, error_w, error_q, error_e, error_l)
    integer, intent(in) :: scheme, n
    real(wp), intent(out) :: error_w, error_q, error_e, error_l
    type(rigid_body_t) :: top
    real(wp) :: dt, precession, exact_w(3), l_lab(3), exact_q(4), e0, lmag0
    integer :: step
    call rigid_body_init(top, 1.0_wp, [i3, i1, i1], [0.0_wp, 0.0_wp, 0.0_wp], q0)
    top%angular_velocity_body = [w3, w_perp, 0.0_wp]
    e0 = kinetic_energy(top)
    l_lab = angular_momentum(top)
    lmag0 = norm2(l_lab)
    dt = total_time / n
    do step = 1, n
      call rigid_body_step(top, [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], dt, merge(integrator_euler, &
                           integrator_verlet, scheme == 1))
    end do
    precession = (i3 - i1) * w3 / i1
    exact_w = [w3, w_perp * cos(precession * total_time), w_perp * sin(precession * total_time)]
    exact_q = quaternion_product(quaternion_from_axis_angle(l_lab / lmag0, lmag0 * total_time / i1), &
              quaternion_product(q0, quaternion_from_axis_angle([1.0_wp, 0.0_wp, 0.0_wp], -precession * total_time)))
    error_w = norm2(top%angular_velocity_body - exact_w)
    error_q = min(norm2(top%quaternion - exact_q), norm2(top%quaternion + exact_q))
    error_e = abs(kinetic_energy(top) - e0) / e0
    error_l = abs(norm2(angular_momentum(top)) - lmag0) / lmag0
  end subroutine run_top
end program test_rigid_body
