! checks: 14
!> &scene substep_bodies = 'near' (particles/near_bodies, coupling/point_particle_coupling
!> point_free_step) against every body sub-stepped ('all'), with the scene loop's organisation of a
!> fluid step (driver/scene_loop, particle_substeps): calcite spheres of radius 2.5 um (Stokes time
!> with the added mass tau = 4.5 us) and a prolate spheroid (aspect ratio 3) in a linear flow
!> u = U0 cos(omega t) + G (x - c), G a straining (-1, 1/2, 1/2) gamma plus a rotation, sampled at
!> the centres at both ends of each fluid step of 40 us (tau / dt = 0.11) as the point provider
!> samples the resolved fluid, with 200 sub-steps of 0.2 us (the suspension deck's). The straining
!> brings a pair on the x axis, 8 um apart, into contact (DLVO and collisions on); three other
!> bodies stay far from everything.
!> - isolated bodies: the one-step exponential update against the 200 explicit Euler sub-steps:
!>   positions within 2e-3 of the distance travelled and velocities within 3e-3 of the velocity
!>   scale U0 (the reference's own error: explicit Euler at h = dt_p / tau = 0.045 lags the
!>   relaxation by about h / 2 of the slip, and the linear-in-time fluid of the sub-steps differs from
!>   the exponential update's held gradient at second order in dt; measured 1.1e-4 and 5.6e-4);
!> - the pair that becomes near: the same outcome in both (collided, held in contact at the end
!>   with a gap below 5 nm, the first impulse in the same fluid step) and its centres within 0.1 um;
!> - the organisation did what it says: the pair took the sub-steps in some fluid steps, the others
!>   one update in every fluid step, and no pair came within the broad phase's gap with a body that
!>   took the one-step update (misses = 0);
!> - a Stokes time 1000 times shorter than the step: the one-step update is stable and lands on the
!>   exact terminal velocity of the uniform flow, u + (rho_f V - m) Du/Dt / zeta (relative 1e-9).
program test_near_substeps
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use parallel_env, only: parallel_start
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler, added_inertia_t
  use quaternion, only: quaternion_identity, quaternion_from_axis_angle
  use config_dlvo, only: dlvo_config_t
  use config_collision, only: collision_config_t
  use dlvo, only: dlvo_setup
  use collision, only: collision_setup
  use particle_system, only: particle_models_t, particle_loads_t, particle_system_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero, &
                             particle_system_set_added_inertia, particle_system_set_members, particle_search_gap, &
                             particle_interaction_gap, wrap_body, unwrapped_position, &
                             particle_system_all_members
  use near_bodies, only: near_bodies_t, near_bodies_find
  use point_particle_coupling, only: point_coupling_t, point_coupling_create, point_fluid_at, point_body_loads, &
                                     point_free_step
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_equal
  implicit none
  real(wp), parameter :: box = 1.0e-3_wp, rho_f = 997.0_wp, mu = rho_f * 1.0e-6_wp, radius = 2.5e-6_wp
  real(wp), parameter :: dt = 4.0e-5_wp, gamma = 1000.0_wp, omega = 2.0_wp * pi * 100.0_wp
  real(wp), parameter :: uniform(3) = [0.02_wp, -0.01_wp, 0.005_wp]
  integer, parameter :: substeps = 200, steps = 40, n = 5
  type(particle_system_t) :: all, near
  type(near_bodies_t) :: finder
  integer :: first_all, first_near, step, i, near_steps
  integer(i8) :: single_updates
  real(wp) :: start(3, n), travel, error_x, error_v

  call parallel_start()
  call test_start('near_substeps')

  call run(all, .false., first_all, near_steps, single_updates)
  call run(near, .true., first_near, near_steps, single_updates)
  do i = 3, n
    travel = norm2(unwrapped_position(all, i) - start(:, i))
    error_x = norm2(unwrapped_position(near, i) - unwrapped_position(all, i)) / travel
    error_v = norm2(near%bodies(i)%velocity - all%bodies(i)%velocity) / norm2(uniform)
    print '(a,i0,a,es10.3,a,es10.3)', '  isolated body ', i, ': position error / travel ', error_x, &
      ', velocity error / U0 ', error_v
    call check_below(error_x, 2.0e-3_wp, 'isolated_body_position_matches_substeps')
    call check_below(error_v, 3.0e-3_wp, 'isolated_body_velocity_matches_substeps')
  end do
  call check(all%collisions_total > 0 .and. near%collisions_total > 0, 'near_pair_collides_in_both')
  call check_equal(first_near, first_all, 'near_pair_first_impulse_same_fluid_step')
  call check_below(max(all%pairs(1)%contact%gap, near%pairs(1)%contact%gap), 5.0e-9_wp, 'near_pair_held_in_both')
  call check_below(max(norm2(unwrapped_position(near, 1) - unwrapped_position(all, 1)), &
                       norm2(unwrapped_position(near, 2) - unwrapped_position(all, 2))), 1.0e-7_wp, &
                   'near_pair_centres_match_substeps')
  print '(a,i0,a,i0)', '  fluid steps with the pair in the sub-steps: ', near_steps, ' of ', steps
  call check(near_steps > 0 .and. near_steps < steps, 'pair_sub_stepped_only_once_near')
  call check(single_updates >= int(3 * steps, i8), 'isolated_bodies_took_one_update_per_step')
  call check_equal(int(finder%misses), 0, 'no_pair_missed')
  call check_short_stokes_time()
  call test_finish()

contains

  !> The five bodies over steps fluid steps; near_only: the 'near' organisation. first: the fluid
  !> step of the first impulse; near_steps: fluid steps with members; single: one-step updates.
  subroutine run(system, near_only, first, near_steps, single)
    type(particle_system_t), intent(out) :: system
    logical, intent(in) :: near_only
    integer, intent(out) :: first, near_steps
    integer(i8), intent(out) :: single
    type(spheroid_t) :: shapes(n)
    type(rigid_body_t) :: bodies(n)
    type(particle_models_t) :: models
    type(point_coupling_t) :: coupling
    type(particle_loads_t) :: loads
    type(added_inertia_t) :: added(n)
    real(wp) :: centre(3), t, dtp
    integer :: s, k
    centre = 0.5_wp * [box, box, box]
    shapes = make_spheroid('sphere', radius, 2710.0_wp)
    shapes(5) = make_spheroid('needle', radius, 2710.0_wp, 3.0_wp)
    start(:, 1) = centre - [radius + 4.0e-6_wp, 0.0_wp, 0.0_wp]
    start(:, 2) = centre + [radius + 4.0e-6_wp, 0.0_wp, 0.0_wp]
    start(:, 3) = centre + [30.0e-6_wp, 150.0e-6_wp, 0.0_wp]
    start(:, 4) = centre + [-30.0e-6_wp, -150.0e-6_wp, 40.0e-6_wp]
    start(:, 5) = centre + [0.0_wp, 60.0e-6_wp, -120.0e-6_wp]
    do k = 1, n
      call rigid_body_of_spheroid(bodies(k), shapes(k), start(:, k), &
                                  quaternion_from_axis_angle([1.0_wp, 2.0_wp, 3.0_wp] / sqrt(14.0_wp), 0.3_wp * k), &
                                  velocity=fluid_velocity(start(:, k), 0.0_wp) + 0.01_wp * [0.0_wp, 1.0_wp, -1.0_wp], &
                                  angular_velocity=[100.0_wp, -50.0_wp, 20.0_wp])
    end do
    models%dlvo = .true.
    call dlvo_setup(models%dlvo_model, dlvo_config_t(), radius)
    models%collisions = .true.
    call collision_setup(models%collision_model, collision_config_t())
    models%integrator = integrator_euler
    models%interaction_gap = particle_interaction_gap(models)
    call particle_system_create(system, shapes, bodies, models, box_length=[box, box, box])
    call point_coupling_create(coupling, shapes, rho_f, mu, [box, box, box], .true.)
    do k = 1, n
      added(k)%mass = coupling%added_mass(:, k)
    end do
    call particle_system_set_added_inertia(system, added)
    dtp = dt / substeps
    call particle_system_interact(system, dtp)
    loads = particle_loads_zero(n)
    first = 0
    near_steps = 0
    single = 0_i8
    do step = 1, steps
      t = (step - 1) * dt
      call sample(coupling, system, t)
      if (near_only) then
        call particle_system_all_members(system)
        call near_bodies_find(finder, system, coupling%velocity(:, :, 1), coupling%velocity(:, :, 2), dt, &
                              particle_search_gap(system, dtp))
        call particle_system_set_members(system, finder%members(1:finder%count))
        if (finder%count > 0) near_steps = near_steps + 1
        do k = 1, n - finder%count
          call point_free_step(coupling, finder%single(k), system%bodies(finder%single(k)), dt)
          call wrap_body(system, finder%single(k))
        end do
        single = single + (n - finder%count)
      end if
      call loads_of(coupling, system, near_only, 0.0_wp, loads)
      do s = 1, substeps
        call particle_system_step(system, dtp, loads)
        call loads_of(coupling, system, near_only, real(s, wp) / substeps, loads)
      end do
      if (first == 0 .and. system%collisions_total > 0) first = step
    end do
  end subroutine run

  !> The linear flow at x and t (program header).
  pure function fluid_velocity(x, t) result(u)
    real(wp), intent(in) :: x(3), t
    real(wp) :: u(3)
    u = uniform * cos(omega * t) + matmul(gradient(), x - 0.5_wp * [box, box, box])
  end function fluid_velocity

  pure function gradient() result(g)
    real(wp) :: g(3, 3)
    g = 0.0_wp
    g(1, 1) = -gamma
    g(2, 2) = 0.5_wp * gamma
    g(3, 3) = 0.5_wp * gamma
    g(1, 2) = 0.2_wp * gamma      ! plus a rotation about z
    g(2, 1) = -0.2_wp * gamma
  end function gradient

  !> The point provider's samples of the fluid step from t to t + dt at the current centres.
  subroutine sample(coupling, system, t)
    type(point_coupling_t), intent(inout) :: coupling
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: t
    integer :: k
    do k = 1, n
      coupling%anchor(:, k) = system%bodies(k)%position
      coupling%velocity(:, k, 1) = fluid_velocity(coupling%anchor(:, k), t)
      coupling%velocity(:, k, 2) = fluid_velocity(coupling%anchor(:, k), t + dt)
      coupling%gradient(:, :, k, 1) = gradient()
      coupling%gradient(:, :, k, 2) = gradient()
    end do
    coupling%dt = dt
  end subroutine sample

  !> The loads of the sub-steps: every body's, or the members' (the scene loop's felt_loads).
  subroutine loads_of(coupling, system, near_only, theta, loads)
    type(point_coupling_t), intent(in) :: coupling
    type(particle_system_t), intent(in) :: system
    logical, intent(in) :: near_only
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
    integer :: k, i
    do k = 1, merge(finder%count, system%n, near_only)
      i = merge(finder%members(k), k, near_only)
      call point_body_loads(coupling, i, system%bodies(i), point_fluid_at(coupling, i, system%bodies(i)%position, theta), &
                            system%dlvo_loads%force(:, i), loads%force(:, i), loads%torque(:, i))
    end do
  end subroutine loads_of

  !> A sphere with tau = dt / 1000 in a uniform, steadily accelerating flow u = u0 + a t: one update
  !> of dt lands on the terminal slip velocity (m + m_a) a = zeta (u - U) + (rho_f V + m_a) a.
  subroutine check_short_stokes_time()
    type(spheroid_t) :: tiny(1)
    type(rigid_body_t) :: body
    type(point_coupling_t) :: coupling
    real(wp), parameter :: u0(3) = [0.01_wp, 0.0_wp, -0.02_wp], accel(3) = [5.0_wp, -3.0_wp, 1.0_wp]
    real(wp) :: zeta, expected(3), tau, a
    ! tau = (m + m_f / 2) / (6 pi mu a) = a^2 (2 rho_p + rho_f) / (9 mu): a for tau = dt / 1000.
    a = sqrt(9.0_wp * mu * dt / 1000.0_wp / (2.0_wp * 2710.0_wp + rho_f))
    tiny(1) = make_spheroid('sphere', a, 2710.0_wp)
    call point_coupling_create(coupling, tiny, rho_f, mu, [box, box, box], .true.)
    coupling%anchor(:, 1) = 0.5_wp * [box, box, box]
    coupling%velocity(:, 1, 1) = u0
    coupling%velocity(:, 1, 2) = u0 + accel * dt
    coupling%dt = dt
    call rigid_body_of_spheroid(body, tiny(1), coupling%anchor(:, 1), quaternion_identity, velocity=[0.0_wp, 0.0_wp, 0.0_wp])
    call point_free_step(coupling, 1, body, dt)
    zeta = 6.0_wp * pi * mu * a
    tau = (tiny(1)%mass + 0.5_wp * coupling%fluid_mass(1)) / zeta
    print '(a,es10.3)', '  tau / dt = ', tau / dt
    expected = u0 + accel * dt + (coupling%fluid_mass(1) - tiny(1)%mass) * accel / zeta
    call check_below(norm2(body%velocity - expected) / norm2(u0 + accel * dt), 1.0e-9_wp, &
                     'short_stokes_time_terminal_velocity')
  end subroutine check_short_stokes_time
end program test_near_substeps
