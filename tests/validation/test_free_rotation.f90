! checks: 5
!> Rotational added inertia of a free disk resolved by the immersed boundary (docs/studies/validation.md,
!> "Free particles"): a disk (aspect ratio 5) spun about a diameter in fluid at rest, no other load.
!> Its potential-flow rotational added inertia about a diameter is 1.79 rho_f/rho_p of its own
!> (Lamb 1932 sec. 373; resolved_hydrodynamics: rotational_added_inertia): at the density ratio
!> 0.3, 6 times its own. With the lagged torque alone (&scene added_mass off) the spin must flip
!> sign from step to step with a growing amplitude (the explicit added-inertia instability). With
!> the stabilisation, at the density ratios 0.5 and 1 (the light particles the deck accepts) and
!> 2.72 (added inertia 0.66 of its own), it must stay below its start value over 30 fluid steps;
!> at 2.72 without a sign change. (At 0.3 the stabilised spin rings with a slowly growing amplitude:
!> the deck refuses density ratios below 0.5, docs/studies/validation.md.)
program test_free_rotation
  use agglo_kinds, only: wp
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use parallel_env, only: parallel_start
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use forcing_driver, only: forcing_driver_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler, angular_velocity_lab
  use particle_system, only: particle_system_t, particle_models_t, particle_loads_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero
  use immersed_boundary, only: ibm_settings_t
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create, &
                                    resolved_hydrodynamics_options_t
  use test_framework, only: test_start, test_finish, check
  implicit none
  integer, parameter :: steps = 30
  real(wp) :: spin(steps), largest
  integer :: flips, taken
  character(len=160) :: text

  call parallel_start()
  call test_start('free_rotation')

  call spin_down(0.3_wp, .false., spin, taken)
  largest = maxval(abs(spin(1:taken)))
  flips = count(spin(1:taken - 1) * spin(2:taken) < 0.0_wp)
  write(text, '(a,es10.3,a,i0,a,i0,a)') 'ratio 0.3, lagged torque: max |Omega| / Omega_0 ', largest, ', ', flips, &
      ' sign flips in ', taken, ' steps'
  print '(a)', trim(text)
  call check(largest > 10.0_wp .and. flips >= taken / 2, 'light_disk_spin_unstable_without_stabilisation', trim(text))

  call stays_bounded(0.5_wp, 'half_density_disk_spin_bounded_with_stabilisation')
  call stays_bounded(1.0_wp, 'neutral_disk_spin_bounded_with_stabilisation')
  call stays_bounded(2.72_wp, 'calcite_disk_spin_bounded_with_stabilisation')
  call spin_down(2.72_wp, .true., spin, taken)
  flips = count(spin(1:taken - 1) * spin(2:taken) < 0.0_wp)
  call check(flips == 0, 'calcite_disk_spin_keeps_its_sign')
  call test_finish()

contains

  !> With the stabilisation the spin never exceeds its start value and ends below it.
  subroutine stays_bounded(density_ratio, name)
    real(wp), intent(in) :: density_ratio
    character(len=*), intent(in) :: name
    call spin_down(density_ratio, .true., spin, taken)
    largest = maxval(abs(spin(1:taken)))
    write(text, '(a,f5.2,a,f7.4,a,f7.4,a,i0,a)') 'ratio ', density_ratio, ', stabilised: max |Omega| / Omega_0 ', &
        largest, ', last ', spin(taken), ' after ', taken, ' steps'
    print '(a)', trim(text)
    call check(taken == steps .and. largest <= 1.0_wp .and. abs(spin(taken)) < 1.0_wp, name, trim(text))
  end subroutine stays_bounded

  !> Omega_y / Omega_0 after each fluid step of the disk spun at Omega_0 about its diameter y; a
  !> run whose spin exceeds 100 Omega_0 or is not finite stops there (taken: the steps recorded).
  subroutine spin_down(density_ratio, stabilise, spin, taken)
    real(wp), intent(in) :: density_ratio
    logical, intent(in) :: stabilise
    real(wp), intent(out) :: spin(:)
    integer, intent(out) :: taken
    ! Water-like units in a 1 mm cell of 40^3: the disk 4.4 cells thick, 22 across; rim speed 1e-4 m/s.
    real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, thickness = 110.0e-6_wp
    integer, parameter :: cells = 40, substeps = 4
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(forcing_driver_t) :: forcing                  ! inactive
    type(spheroid_t) :: shape(1)
    type(rigid_body_t) :: body(1)
    type(particle_models_t) :: models
    type(particle_system_t) :: system
    type(particle_loads_t) :: loads
    type(ibm_settings_t) :: settings
    type(resolved_hydrodynamics_t) :: provider
    real(wp) :: omega0, dt, omega(3)
    integer :: step, substep
    grid_cfg = grid_config_t(nx=cells, ny=cells, nz=cells, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = 'explicit'
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    ! a = thickness / 2, b = 5 a, r^3 = a b^2.
    shape(1) = make_spheroid('disk', 0.5_wp * thickness * 25.0_wp**(1.0_wp / 3.0_wp), density_ratio * density, 5.0_wp)
    omega0 = 1.0e-4_wp / shape(1)%b
    call rigid_body_of_spheroid(body(1), shape(1), 0.5_wp * box + [0.13_wp, 0.27_wp, 0.41_wp] * solver%grid%dx, &
                                [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, omega0, 0.0_wp])
    models%integrator = integrator_euler
    call particle_system_create(system, shape, body, models, [box, box, box])
    call particle_system_interact(system, 1.0_wp)
    settings%coupling = 'implicit'
    settings%tolerance = 1.0e-12_wp
    settings%max_sweeps = 100
    settings%fluid_density = density
    call resolved_hydrodynamics_create(provider, solver, system, resolved_hydrodynamics_options_t(settings=settings, &
                                       stabilise=stabilise))
    call provider%prepare(solver, system)
    loads = particle_loads_zero(1)
    dt = 0.06_wp * solver%grid%dx**2 / viscosity
    spin = 0
    taken = 0
    do step = 1, size(spin)
      call provider%fluid_step(solver, forcing, system, dt)
      do substep = 1, substeps
        call provider%loads(system, real(substep - 1, wp) / substeps, loads)
        call particle_system_step(system, dt / substeps, loads)
      end do
      omega = angular_velocity_lab(system%bodies(1))
      taken = step
      spin(step) = omega(2) / omega0
      if (.not. ieee_is_finite(spin(step)) .or. abs(spin(step)) > 100.0_wp) exit
    end do
  end subroutine spin_down
end program test_free_rotation
