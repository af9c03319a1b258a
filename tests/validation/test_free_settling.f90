!> A free sphere settling in the periodic box, resolved by the immersed boundary (docs/validation.md,
!> "Free particles"): one sphere per cell is a simple-cubic array, so at steady state its slip
!> velocity is the one at which the array's Stokes drag balances the net weight W:
!>   W = 6 pi mu a K(phi) U_s,   U_s = U_p - U_face (the superficial velocity relative to the sphere,
!> U_face the flux through the box's x-face over its area, a plane the sphere never cuts), with the
!> Zick & Homsy (1982, J. Fluid Mech. 115, 13, Table 2) K = 4.292 at phi = 0.125. The same cell,
!> D/dx = 8.06 (13^3), as the fixed-sphere array of test_immersed_stokes (K = 4.2794, -0.29%,
!> docs/validation.md "Immersed boundary"): the free sphere's K must agree with the fixed array's to
!> 0.5% and with Zick & Homsy to 1%. The gravity path of module resolved_hydrodynamics: the net
!> weight on the sphere and the opposite drive -W / L^3 over the box; the added-mass stabilisation on.
!> Also: the potential-flow added masses the stabilisation uses (sphere k = 1/2; the face-on disk of
!> aspect ratio 5 at the calcite density ratio, added mass / mass = 1.11, ibm-notes section 6) and
!> the rotational added inertia (zero for a sphere; for the disk about a diameter a fraction of the
!> disk's own inertia, below 1 at the calcite ratio: the rotation stays explicitly stable).
program test_free_settling
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: parallel_start, global_sum
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use forcing_driver, only: forcing_driver_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use particle_system, only: particle_system_t, particle_models_t, particle_loads_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero
  use stokes_resistance, only: spheroid_added_mass_coefficients
  use immersed_boundary, only: ibm_settings_t
  use immersed_geometry, only: node_fluid
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create, rotational_added_inertia
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp   ! Zick & Homsy 1982, Table 2, phi = 0.125
  real(wp), parameter :: fixed_array_13 = 4.2794_wp   ! the fixed sphere at 13^3 (docs/validation.md)
  ! Water-like units in a 1 mm cell, as the fixed-sphere array (sphere_array_case); the weight makes
  ! U_s about 1e-7 m/s: Re = U_s D / nu below 1e-4.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, particle_density = 2720.0_wp
  real(wp), parameter :: phi = 0.125_wp, weight_target = 2.5e-12_wp
  integer, parameter :: cells = 13, max_steps = 6000, substeps = 4
  type(grid_config_t) :: grid_cfg
  type(fluid_config_t) :: fluid_cfg
  type(fluid_solver_t) :: solver
  type(forcing_driver_t) :: forcing                  ! inactive
  type(spheroid_t) :: shape(1), disk
  type(rigid_body_t) :: body(1)
  type(particle_models_t) :: models
  type(particle_system_t) :: system
  type(particle_loads_t) :: loads
  type(ibm_settings_t) :: settings
  type(resolved_hydrodynamics_t) :: provider
  real(wp) :: radius, gravity(3), weight, dt, slip, slip_old, u_face, drag_coefficient, k(2), ratio, momentum, fluid_flux
  integer :: step, substep
  logical :: steady
  character(len=160) :: text

  call parallel_start()
  call test_start('free_settling')

  ! The coefficients the stabilisation uses.
  k = spheroid_added_mass_coefficients(1.0_wp, 1.0_wp)
  call check_close(k(1), 0.5_wp, 1.0e-10_wp, 'sphere_added_mass_one_half')
  disk = make_spheroid('disk', 50.0e-6_wp, 2710.0_wp, 5.0_wp)
  k = spheroid_added_mass_coefficients(disk%a, disk%b)
  ratio = k(1) * 997.0_wp / 2710.0_wp
  write(text, '(a,f6.3)') 'face-on disk (aspect 5) added mass / mass at 2710/997: ', ratio
  print '(a)', trim(text)
  call check_close(ratio, 1.107_wp, 0.01_wp, 'face_on_disk_added_mass_ratio_ibm_notes')
  shape(1) = make_spheroid('sphere', 50.0e-6_wp, 2710.0_wp)
  call check_below(abs(rotational_added_inertia(shape(1), 997.0_wp)), 1.0e-30_wp, 'sphere_no_rotational_added_inertia')
  call rigid_body_of_spheroid(body(1), disk, [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], &
                              [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
  ratio = rotational_added_inertia(disk, 997.0_wp) / body(1)%inertia_body(2)
  write(text, '(a,f6.3)') 'disk (aspect 5) rotational added inertia / inertia about a diameter at 2710/997: ', ratio
  print '(a)', trim(text)
  call check(ratio > 0.1_wp .and. ratio < 1.0_wp, 'disk_rotational_added_inertia_below_own_at_calcite')

  ! The settling sphere.
  grid_cfg = grid_config_t(nx=cells, ny=cells, nz=cells, length_x=box, length_y=box, length_z=box)
  fluid_cfg%density = density
  fluid_cfg%viscosity = viscosity
  fluid_cfg%viscous_scheme = 'explicit'
  fluid_cfg%pressure_scheme = 'incremental'
  call fluid_solver_create(solver, grid_cfg, fluid_cfg)
  solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
  radius = (3.0_wp * phi / (4.0_wp * pi))**(1.0_wp / 3.0_wp) * box
  shape(1) = make_spheroid('sphere', radius, particle_density)
  call rigid_body_of_spheroid(body(1), shape(1), 0.5_wp * box + [0.13_wp, 0.27_wp, 0.41_wp] * solver%grid%dx, &
                              [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
  models%integrator = integrator_euler
  call particle_system_create(system, shape, body, models, [box, box, box])
  call particle_system_interact(system, 1.0_wp)
  gravity = [weight_target / ((particle_density - density) * shape(1)%volume), 0.0_wp, 0.0_wp]
  weight = (particle_density - density) * shape(1)%volume * gravity(1)
  settings%coupling = 'implicit'
  settings%tolerance = 1.0e-12_wp
  settings%max_sweeps = 100
  settings%fluid_density = density
  call resolved_hydrodynamics_create(provider, solver, system, settings, 'momentum', -1, stabilise=.true., &
                                     restart=.false., gravity=gravity)
  call provider%prepare(solver, system)
  loads = particle_loads_zero(1)
  dt = 0.06_wp * solver%grid%dx**2 / viscosity
  slip_old = 0
  steady = .false.
  do step = 1, max_steps
    call provider%fluid_step(solver, forcing, system, dt)
    do substep = 1, substeps
      call provider%loads(system, real(substep - 1, wp) / substeps, loads)
      call particle_system_step(system, dt / substeps, loads)
    end do
    u_face = global_sum(sum(solver%u(solver%grid%nx, 1:solver%grid%ny, 1:solver%grid%nz_local))) / real(cells**2, wp)
    slip = system%bodies(1)%velocity(1) - u_face
    if (step > 50 .and. abs(slip - slip_old) <= 1.0e-8_wp * abs(slip)) then
      steady = .true.
      exit
    end if
    slip_old = slip
  end do
  drag_coefficient = weight / (6.0_wp * pi * density * viscosity * radius * slip)
  write(text, '(a,f6.2,a,es10.3,a,f7.4,a,f6.2,a,f6.2,a,i0)') 'settling sphere D/dx ', 2 * radius / solver%grid%dx, &
      ' slip ', slip, ' m/s K ', drag_coefficient, ' vs Z&H ', 100 * (drag_coefficient / zick_homsy_0125 - 1), &
      '%, vs fixed array ', 100 * (drag_coefficient / fixed_array_13 - 1), '% steps ', step
  print '(a)', trim(text)
  call check(steady, 'settling_sphere_reaches_terminal_velocity')
  call check_close(drag_coefficient, fixed_array_13, 0.005_wp, 'settling_sphere_drag_equals_fixed_array_0p5pc')
  call check_close(drag_coefficient, zick_homsy_0125, 0.01_wp, 'settling_sphere_drag_zick_homsy_1pc')
  ! The drive balances the weight, so the box's momentum stays at its start value, zero: the fluid
  ! nodes' rho_f dV sum u plus the sphere's m U_p (the fictitious fluid on the sphere's ghost and
  ! interior nodes is no momentum of the physical system; the loads by momentum balance account
  ! for it, docs/theory.md).
  associate (status => provider%scene%ibm%geometry%component(1)%status)
    fluid_flux = global_sum(sum(solver%u(1:cells, 1:cells, 1:solver%grid%nz_local), &
                                mask=status(1:cells, 1:cells, 1:solver%grid%nz_local) == node_fluid))
  end associate
  momentum = (density * solver%grid%dx * solver%grid%dy * solver%grid%dz * fluid_flux &
              + system%bodies(1)%mass * system%bodies(1)%velocity(1)) / (density * box**3 * slip)
  write(text, '(a,es10.3)') 'box momentum / (rho_f L^3 slip): ', momentum
  print '(a)', trim(text)
  call check_below(abs(momentum), 1.0e-6_wp, 'settling_box_momentum_stays_zero')
  call test_finish()
end program test_free_settling
