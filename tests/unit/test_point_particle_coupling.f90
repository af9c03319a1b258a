! checks: 45
!> Point-particle coupling (coupling/point_particle_coupling) through the particle system's step:
!> - a sphere released at rest in a uniform flow relaxes to the fluid velocity as
!>   U - v(t) = U exp(-t / tau), tau = m / (6 pi mu a) (Stokes drag, quasi-steady), and with the
!>   added mass as tau = (m + m_f / 2) / (6 pi mu a); a face-on disk LIGHTER than water (density
!>   ratio 0.5, added mass k rho_f V about 6 times its mass) relaxes stably with
!>   tau = (m + k_ax rho_f V) / zeta_ax. Tolerance 2e-3 at t = tau, 2 tau, 3 tau: explicit Euler at
!>   h = dt / tau = 1e-3 gives (1 - h)^k = exp(-k h) (1 - k h^2 / 2 + ...), 1.5e-3 at k h = 3;
!> - a sphere at rest in a frozen Taylor-Green field u = U (sin kx cos ky, -cos kx sin ky, 0):
!>   force 6 pi mu a u + rho_f V (u . grad) u with (u . grad) u = (U^2 k / 2)(sin 2kx, sin 2ky, 0),
!>   torque 8 pi mu a^3 (1/2) curl u with (1/2) curl u = (0, 0, U k sin kx sin ky); within 2% of the
!>   scale (U, U^2 k) at 32 cells per period and 0.5% at 64 (trilinear interpolation and centred
!>   differences: second order, error about (k dx)^2 / 8 = 0.5% at 32 cells);
!> - a neutrally buoyant sphere with added mass, released with the fluid's velocity in the frozen
!>   Taylor-Green field, moves with the fluid (U = u is an exact solution of the point model when
!>   rho_p = rho_f: (m + k m_f) dU/dt = zeta (u - U) + (1 + k) m_f Du/Dt): over 0.1 s (0.14 mm
!>   along its streamline) its streamfunction psi = (U/k) sin kx sin ky stays within 1% of U/k and
!>   its velocity within 0.5% of U of the interpolated fluid velocity (32 cells per period:
!>   interpolation 0.5%; explicit Euler's lag). Without the rho_f V Du/Dt term the sphere would lag
!>   by (1 + k) m_f |Du/Dt| / zeta, about 1.3% of U here, and fail;
!> - the time interpolation between the samples: at theta = 1/4 of a step from u = 0 to u = U the
!>   fluid moves at U / 4 and accelerates at U / dt (round-off);
!> - a body that crossed the periodic boundary since its anchor reads the flow at its own side;
!> - a face-on calcite disk held by its DLVO attraction against an edge-on one in fluid at rest
!>   (collisions e = 0.4, 2 ms of 2e-7 s steps): the pair's centre stays where it was, as it must
!>   under internal forces alone: moved by less than 0.1 nm (measured 3e-14 m; the bodies' contact
!>   oscillation moves each at up to 1e-7 m/s). With contact impulses that moved each body with its
!>   own mass while the loads move it with m + M_a (before the impulses carried the added mass), the
!>   held pair drifted along the normal under the difference of the two added masses' shares of the
!>   attraction: 0.89 um in 2 ms, at 0.75 mm/s at the end;
!> - added-mass coefficients: sphere 1/2; limits of Lamb (1932) sec. 373: a thin oblate disk
!>   face-on k = 2 b / (pi a) (added mass 8/3 rho_f b^3), a slender needle transverse k = 1, axial 0.
program test_point_particle_coupling
  use agglo_kinds, only: wp
  use physical_constants, only: pi, two_pi
  use parallel_env, only: parallel_start
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler, added_inertia_t
  use quaternion, only: quaternion_identity, quaternion_from_axis_angle
  use config_dlvo, only: dlvo_config_t
  use config_collision, only: collision_config_t
  use dlvo, only: dlvo_setup
  use collision, only: collision_setup
  use stokes_resistance, only: spheroid_added_mass_coefficients, stokes_resistance_of
  use particle_system, only: particle_models_t, particle_loads_t, particle_system_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero, &
                             particle_system_set_added_inertia
  use point_particle_coupling, only: point_coupling_t, point_fluid_t, point_coupling_create, point_coupling_sample, &
                                     point_fluid_at, point_body_loads, sample_start, sample_end
  use test_framework, only: test_start, test_finish, check_close, check_below, check_above
  implicit none
  real(wp), parameter :: box = 1.0e-3_wp, rho_f = 997.0_wp, nu = 1.0e-6_wp, mu = rho_f * nu
  real(wp), parameter :: radius = 50.0e-6_wp
  real(wp) :: k(2)

  call parallel_start()
  call test_start('point_particle_coupling')

  call check_relaxation('sphere', 2710.0_wp, .false., 'sphere_uniform_flow_stokes_time')
  call check_relaxation('sphere', 2710.0_wp, .true., 'sphere_uniform_flow_with_added_mass')
  call check_relaxation('disk', 0.5_wp * rho_f, .true., 'light_disk_face_on_added_mass_stable')
  call check_taylor_green(32, 0.02_wp, 'taylor_green_32')
  call check_taylor_green(64, 0.005_wp, 'taylor_green_64')
  call check_time_interpolation()
  call check_tracer()
  call check_held_pair_at_rest()

  k = spheroid_added_mass_coefficients(radius, radius)
  call check_close(k(1), 0.5_wp, 1.0e-12_wp, 'added_mass_sphere_axial')
  call check_close(k(2), 0.5_wp, 1.0e-12_wp, 'added_mass_sphere_transverse')
  k = spheroid_added_mass_coefficients(1.0e-3_wp * radius, radius)
  call check_close(k(1) * pi * 1.0e-3_wp / 2.0_wp, 1.0_wp, 0.01_wp, 'added_mass_thin_disk_face_on')
  k = spheroid_added_mass_coefficients(radius, 1.0e-3_wp * radius)
  call check_close(k(2), 1.0_wp, 0.01_wp, 'added_mass_slender_needle_transverse')
  call check_below(k(1), 0.01_wp, 'added_mass_slender_needle_axial')
  call test_finish()

contains

  !> One body at rest in a uniform flow along its symmetry axis (body x = lab x): U - v(t) against
  !> U exp(-t / tau), tau from the resistance and the (added) mass.
  subroutine check_relaxation(shape_name, density, added_mass, name)
    character(len=*), intent(in) :: shape_name, name
    real(wp), intent(in) :: density
    logical, intent(in) :: added_mass
    real(wp), parameter :: flow(3) = [2.0e-3_wp, 0.0_wp, 0.0_wp]
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
    type(spheroid_t) :: shape
    type(rigid_body_t) :: body(1)
    type(particle_system_t) :: system
    type(point_coupling_t) :: coupling
    type(particle_loads_t) :: loads
    real(wp) :: tau, dt, ka(2), mass
    integer :: step, per_tau, checkpoint
    call make_fields(16, grid, u, v, w)
    u = flow(1)
    if (shape_name == 'sphere') then
      shape = make_spheroid('sphere', radius, density)
    else
      shape = make_spheroid(shape_name, radius, density, 5.0_wp)
    end if
    call rigid_body_of_spheroid(body(1), shape, [0.3_wp, 0.6_wp, 0.45_wp] * box, quaternion_identity)
    call particle_system_create(system, [shape], body, particle_models_t(integrator=integrator_euler), &
                                box_length=[box, box, box])
    call particle_system_interact(system, 1.0_wp)
    call point_coupling_create(coupling, [shape], rho_f, mu, [box, box, box], added_mass)
    mass = shape%mass
    if (added_mass) then
      ka = spheroid_added_mass_coefficients(shape%a, shape%b)
      mass = mass + ka(1) * rho_f * shape%volume
    end if
    associate (resistance => stokes_resistance_of(shape, mu))
      tau = mass / resistance%translational(1)
    end associate
    per_tau = 1000
    dt = tau / per_tau
    loads = particle_loads_zero(1)
    call point_coupling_sample(coupling, grid, u, v, w, system%bodies, sample_start)
    call point_coupling_sample(coupling, grid, u, v, w, system%bodies, sample_end, dt)
    do checkpoint = 1, 3
      do step = 1, per_tau
        call loads_of(coupling, system, 0.0_wp, loads)
        call particle_system_step(system, dt, loads)
      end do
      call check_close((flow(1) - system%bodies(1)%velocity(1)) / flow(1), exp(-real(checkpoint, wp)), 2.0e-3_wp, &
                       name//'_t'//achar(iachar('0') + checkpoint)//'tau')
    end do
    call check_below(maxval(abs(system%bodies(1)%velocity(2:3))), 1.0e-12_wp * flow(1), name//'_stays_on_axis')
  end subroutine check_relaxation

  !> Force and torque on a sphere at rest in the frozen Taylor-Green field, against the analytic ones.
  subroutine check_taylor_green(n, tolerance, name)
    integer, intent(in) :: n
    real(wp), intent(in) :: tolerance
    character(len=*), intent(in) :: name
    real(wp), parameter :: amplitude = 5.0e-3_wp
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
    type(spheroid_t) :: shape
    type(rigid_body_t) :: body(1)
    type(point_coupling_t) :: coupling
    type(point_fluid_t) :: fluid
    real(wp) :: x(3), wave, expected_force(3), expected_torque(3), force(3), torque(3), drag, mf, rot
    integer :: i, j, kk, d
    call make_fields(n, grid, u, v, w)
    wave = two_pi / box
    do kk = 0, grid%nz_local + 1
      do j = 0, n + 1
        do i = 0, n + 1
          u(i, j, kk) = amplitude * sin(wave * i * grid%dx) * cos(wave * (j - 0.5_wp) * grid%dy)
          v(i, j, kk) = -amplitude * cos(wave * (i - 0.5_wp) * grid%dx) * sin(wave * j * grid%dy)
        end do
      end do
    end do
    shape = make_spheroid('sphere', radius, 2710.0_wp)
    x = [0.31_wp, 0.17_wp, 0.55_wp] * box
    call rigid_body_of_spheroid(body(1), shape, x, quaternion_identity)
    call point_coupling_create(coupling, [shape], rho_f, mu, [box, box, box], .false.)
    call point_coupling_sample(coupling, grid, u, v, w, body, sample_start)
    call point_coupling_sample(coupling, grid, u, v, w, body, sample_end, 1.0e-4_wp)
    fluid = point_fluid_at(coupling, 1, x, 0.5_wp)
    call point_body_loads(coupling, 1, body(1), fluid, [0.0_wp, 0.0_wp, 0.0_wp], force, torque)
    drag = 6.0_wp * pi * mu * radius
    mf = rho_f * shape%volume
    rot = 8.0_wp * pi * mu * radius**3
    expected_force = drag * amplitude * [sin(wave * x(1)) * cos(wave * x(2)), -cos(wave * x(1)) * sin(wave * x(2)), &
                                         0.0_wp] &
                     + mf * 0.5_wp * amplitude**2 * wave * [sin(2 * wave * x(1)), sin(2 * wave * x(2)), 0.0_wp]
    expected_torque = rot * [0.0_wp, 0.0_wp, amplitude * wave * sin(wave * x(1)) * sin(wave * x(2))]
    do d = 1, 3
      call check_close(force(d), expected_force(d), 0.0_wp, name//'_force_'//achar(iachar('w') + d), &
                       abs_tol=tolerance * (drag * amplitude + mf * amplitude**2 * wave))
      call check_close(torque(d), expected_torque(d), 0.0_wp, name//'_torque_'//achar(iachar('w') + d), &
                       abs_tol=tolerance * rot * amplitude * wave)
    end do
    ! A body just across the x = 0 boundary from its anchor reads the flow on its own side.
    x = [0.002_wp, 0.4_wp, 0.5_wp] * box
    call rigid_body_of_spheroid(body(1), shape, x, quaternion_identity)
    call point_coupling_sample(coupling, grid, u, v, w, body, sample_start)
    call point_coupling_sample(coupling, grid, u, v, w, body, sample_end, 1.0e-4_wp)
    fluid = point_fluid_at(coupling, 1, [0.999_wp * box, x(2), x(3)], 0.0_wp)
    call check_close(fluid%velocity(1), amplitude * sin(-0.001_wp * box * wave) * cos(wave * x(2)), 0.0_wp, &
                     name//'_across_periodic_boundary', abs_tol=tolerance * amplitude)
  end subroutine check_taylor_green

  !> Linear in time between the samples: u = 0 at the start, U at the end of a step dt.
  subroutine check_time_interpolation()
    real(wp), parameter :: flow(3) = [1.0e-3_wp, -2.0e-3_wp, 0.5e-3_wp], dt = 1.0e-4_wp
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
    type(spheroid_t) :: shape
    type(rigid_body_t) :: body(1)
    type(point_coupling_t) :: coupling
    type(point_fluid_t) :: fluid
    real(wp) :: force(3), torque(3), expected(3)
    integer :: d
    call make_fields(8, grid, u, v, w)
    shape = make_spheroid('sphere', radius, 2710.0_wp)
    call rigid_body_of_spheroid(body(1), shape, [0.5_wp, 0.5_wp, 0.5_wp] * box, quaternion_identity)
    call point_coupling_create(coupling, [shape], rho_f, mu, [box, box, box], .false.)
    call point_coupling_sample(coupling, grid, u, v, w, body, sample_start)
    u = flow(1); v = flow(2); w = flow(3)
    call point_coupling_sample(coupling, grid, u, v, w, body, sample_end, dt)
    fluid = point_fluid_at(coupling, 1, body(1)%position, 0.25_wp)
    call point_body_loads(coupling, 1, body(1), fluid, [0.0_wp, 0.0_wp, 0.0_wp], force, torque)
    expected = 6.0_wp * pi * mu * radius * 0.25_wp * flow + rho_f * shape%volume * flow / dt
    do d = 1, 3
      call check_close(fluid%velocity(d), 0.25_wp * flow(d), 1.0e-12_wp, &
                       'time_interpolated_velocity_'//achar(iachar('w') + d))
      call check_close(fluid%acceleration(d), flow(d) / dt, 1.0e-12_wp, 'time_difference_acceleration_'// &
                       achar(iachar('w') + d))
      call check_close(force(d), expected(d), 1.0e-12_wp, 'time_interpolated_force_'//achar(iachar('w') + d))
    end do
  end subroutine check_time_interpolation

  !> A neutrally buoyant sphere with added mass follows the frozen Taylor-Green flow.
  subroutine check_tracer()
    real(wp), parameter :: amplitude = 5.0e-3_wp, dt = 5.0e-5_wp
    integer, parameter :: substeps = 10, fluid_steps = 200
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :)
    type(spheroid_t) :: shape
    type(rigid_body_t) :: body(1)
    type(particle_system_t) :: system
    type(point_coupling_t) :: coupling
    type(particle_loads_t) :: loads
    type(point_fluid_t) :: fluid
    real(wp) :: wave, psi0, x(3), slip
    integer :: i, j, kk, n, sub
    call make_fields(32, grid, u, v, w)
    wave = two_pi / box
    do kk = 0, grid%nz_local + 1
      do j = 0, 33
        do i = 0, 33
          u(i, j, kk) = amplitude * sin(wave * i * grid%dx) * cos(wave * (j - 0.5_wp) * grid%dy)
          v(i, j, kk) = -amplitude * cos(wave * (i - 0.5_wp) * grid%dx) * sin(wave * j * grid%dy)
        end do
      end do
    end do
    shape = make_spheroid('sphere', radius, rho_f)
    x = [0.3_wp, 0.2_wp, 0.5_wp] * box
    call rigid_body_of_spheroid(body(1), shape, x, quaternion_identity)
    body(1)%velocity = amplitude * [sin(wave * x(1)) * cos(wave * x(2)), -cos(wave * x(1)) * sin(wave * x(2)), 0.0_wp]
    call particle_system_create(system, [shape], body, particle_models_t(integrator=integrator_euler), &
                                box_length=[box, box, box])
    call particle_system_interact(system, dt)
    call point_coupling_create(coupling, [shape], rho_f, mu, [box, box, box], .true.)
    loads = particle_loads_zero(1)
    psi0 = stream_function(amplitude, wave, x)
    slip = 0.0_wp
    do n = 1, fluid_steps
      call point_coupling_sample(coupling, grid, u, v, w, system%bodies, sample_start)
      call point_coupling_sample(coupling, grid, u, v, w, system%bodies, sample_end, substeps * dt)
      do sub = 0, substeps - 1
        call loads_of(coupling, system, real(sub, wp) / substeps, loads)
        call particle_system_step(system, dt, loads)
      end do
      fluid = point_fluid_at(coupling, 1, system%bodies(1)%position, 1.0_wp)
      slip = max(slip, norm2(system%bodies(1)%velocity - fluid%velocity))
    end do
    call check_close(stream_function(amplitude, wave, system%bodies(1)%position), psi0, 0.0_wp, &
                     'tracer_stays_on_its_streamline', abs_tol=0.01_wp * amplitude / wave)
    call check_below(slip, 0.005_wp * amplitude, 'tracer_moves_with_the_fluid')
    call check_above(norm2(system%bodies(1)%position - x), 0.1_wp * box, 'tracer_travelled_across_its_cell')
  end subroutine check_tracer

  !> Body 1 face-on (axis along x), body 2 edge-on (axis along y) 1 nm apart along x, at rest in
  !> fluid at rest, DLVO and collisions on: the centre-of-mass velocity after 2 ms (header).
  subroutine check_held_pair_at_rest()
    real(wp), parameter :: dt = 2.0e-7_wp, gap = 1.0e-9_wp
    integer, parameter :: steps = 10000
    type(spheroid_t) :: disk
    type(rigid_body_t) :: bodies(2)
    type(particle_system_t) :: system
    type(particle_models_t) :: models
    type(point_coupling_t) :: coupling
    type(particle_loads_t) :: loads
    real(wp) :: centre_start(3), centre_shift(3), edge_on(4)
    integer :: step, i
    disk = make_spheroid('disk', radius, 2710.0_wp, 5.0_wp)
    edge_on = quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], 0.5_wp * pi)
    call rigid_body_of_spheroid(bodies(1), disk, [0.5_wp, 0.5_wp, 0.5_wp] * box, quaternion_identity)
    call rigid_body_of_spheroid(bodies(2), disk, [0.5_wp * box + disk%a + disk%b + gap, 0.5_wp * box, 0.5_wp * box], &
                                edge_on)
    models%dlvo = .true.
    call dlvo_setup(models%dlvo_model, dlvo_config_t(), radius)
    models%collisions = .true.
    call collision_setup(models%collision_model, collision_config_t())
    models%integrator = integrator_euler
    call particle_system_create(system, [disk, disk], bodies, models, box_length=[box, box, box])
    call point_coupling_create(coupling, [disk, disk], rho_f, mu, [box, box, box], .true.)
    call particle_system_set_added_inertia(system, point_impulse_masses(coupling))
    call particle_system_interact(system, dt)
    centre_start = 0.5_wp * (system%bodies(1)%position + system%bodies(2)%position)
    loads = particle_loads_zero(2)
    do step = 1, steps
      do i = 1, 2
        call point_body_loads(coupling, i, system%bodies(i), point_fluid_t(), system%dlvo_loads%force(:, i), &
                              loads%force(:, i), loads%torque(:, i))
      end do
      call particle_system_step(system, dt, loads)
    end do
    centre_shift = 0.5_wp * (system%bodies(1)%position + system%bodies(2)%position) - centre_start
    call check_below(system%pairs(1)%contact%gap, 5.0e-9_wp, 'held_disk_pair_stays_in_contact')
    call check_below(norm2(centre_shift), 1.0e-10_wp, 'held_disk_pair_centre_of_mass_at_rest')
  end subroutine check_held_pair_at_rest

  !> The added masses the point coupling's loads move each body with (driver point_hydrodynamics
  !> hands the same to the scene's particle system).
  function point_impulse_masses(coupling) result(added)
    type(point_coupling_t), intent(in) :: coupling
    type(added_inertia_t) :: added(coupling%n)
    integer :: i
    do i = 1, coupling%n
      added(i)%mass = coupling%added_mass(:, i)
    end do
  end function point_impulse_masses

  !> Taylor-Green streamfunction psi = (U/k) sin kx sin ky (u = d psi / dy, v = -d psi / dx).
  pure real(wp) function stream_function(amplitude, wave, position)
    real(wp), intent(in) :: amplitude, wave, position(3)
    stream_function = amplitude / wave * sin(wave * position(1)) * sin(wave * position(2))
  end function stream_function

  subroutine loads_of(coupling, system, theta, loads)
    type(point_coupling_t), intent(in) :: coupling
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
    integer :: i
    do i = 1, system%n
      call point_body_loads(coupling, i, system%bodies(i), &
                            point_fluid_at(coupling, i, system%bodies(i)%position, theta), &
                            system%dlvo_loads%force(:, i), loads%force(:, i), loads%torque(:, i))
    end do
  end subroutine loads_of

  subroutine make_fields(n, grid, u, v, w)
    integer, intent(in) :: n
    type(fluid_grid_t), intent(out) :: grid
    real(wp), allocatable, intent(inout) :: u(:, :, :), v(:, :, :), w(:, :, :)
    call grid_create(grid, n, n, n, box, box, box)
    call allocate_field(grid, u)
    call allocate_field(grid, v)
    call allocate_field(grid, w)
  end subroutine make_fields
end program test_point_particle_coupling
