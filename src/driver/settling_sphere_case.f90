!> The validation case of the free particles (docs/validation.md, "Free particles"): one sphere
!> settling under gravity in the periodic cube (module resolved_hydrodynamics: its net weight W on
!> the sphere, the opposite drive -W / L^3 over the box), i.e. a simple-cubic array seen from the
!> sphere. At steady state the array's Stokes drag balances the weight,
!>   W = 6 pi mu a K U_s,   U_s = U_p - U_face,
!> U_face the flux through the box's x-face over its area (a plane the sphere never cuts, as in
!> sphere_array_case), so K is the same drag coefficient as the fixed array's, against Zick & Homsy
!> (1982, J. Fluid Mech. 115, 13, Table 2). Gravity along x; the weight makes U_s about 1e-7 m/s
!> (Re below 1e-4). Steady: the relative change of U_s per step below steady_tolerance.
!> Also the box's momentum rho_f dV sum_{fluid u nodes} u + m U_p (zero: no net force on the box),
!> over rho_f L^3 U_s.
module settling_sphere_case
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use physical_constants, only: pi
  use parallel_env, only: global_sum
  use wall_clock, only: wall_time
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use forcing_driver, only: forcing_driver_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use particle_system, only: particle_system_t, particle_models_t, particle_loads_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero
  use immersed_boundary, only: ibm_settings_t
  use immersed_geometry, only: node_fluid
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create
  implicit none
  private
  public :: settling_case_t, settling_result_t, run_settling_sphere

  type :: settling_case_t
    integer :: cells = 13                        !< cells per box edge
    real(wp) :: volume_fraction = 0.125_wp       !< phi = V_sphere / L^3
    real(wp) :: density_ratio = 2.72_wp          !< rho_p / rho_f
    logical :: stabilise = .true.                !< the added-mass stabilisation
    integer :: substeps = 4                      !< particle sub-steps per fluid step
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2
    character(len=16) :: viscous_scheme = 'explicit'   !< &fluid viscous_scheme: 'explicit' | 'crank_nicolson'
    real(wp) :: steady_tolerance = 1.0e-8_wp
    integer :: max_steps = 20000
    real(wp) :: offset_cells(3) = [0.13_wp, 0.27_wp, 0.41_wp]   !< sphere centre - box centre, cells
  end type settling_case_t

  type :: settling_result_t
    real(wp) :: drag_coefficient = 0       !< K = W / (6 pi mu a U_s)
    real(wp) :: diameter_cells = 0         !< D / dx
    real(wp) :: slip = 0                   !< m/s, U_s
    real(wp) :: momentum = 0               !< the box's momentum / (rho_f L^3 U_s)
    integer :: steps = 0
    logical :: steady = .false.
    real(wp) :: wall_seconds = 0
  end type settling_result_t

  ! Water-like units in a 1 mm cell, as sphere_array_case; W = 2.5e-12 N gives U_s about 1e-7 m/s.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, weight = 2.5e-12_wp

contains

  !> Run the case to steady state (collective).
  subroutine run_settling_sphere(case, result)
    type(settling_case_t), intent(in) :: case
    type(settling_result_t), intent(out) :: result
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
    real(wp) :: radius, gravity(3), dt, slip, slip_old, u_face, fluid_flux, t0
    integer :: step, substep, n, nz

    t0 = wall_time()
    if (.not. abs(case%density_ratio - 1.0_wp) > 1.0e-3_wp) &
      call fatal('settling_sphere_case: density_ratio 1 has no net weight to settle under')
    n = case%cells
    grid_cfg = grid_config_t(nx=n, ny=n, nz=n, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = case%viscous_scheme
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    nz = solver%grid%nz_local
    radius = (3.0_wp * case%volume_fraction / (4.0_wp * pi))**(1.0_wp / 3.0_wp) * box
    shape(1) = make_spheroid('sphere', radius, case%density_ratio * density)
    call rigid_body_of_spheroid(body(1), shape(1), 0.5_wp * box + case%offset_cells * solver%grid%dx, &
                                [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    models%integrator = integrator_euler
    call particle_system_create(system, shape, body, models, [box, box, box])
    call particle_system_interact(system, 1.0_wp)
    gravity = [weight / ((case%density_ratio - 1.0_wp) * density * shape(1)%volume), 0.0_wp, 0.0_wp]
    settings%coupling = 'implicit'
    settings%tolerance = 1.0e-12_wp
    settings%max_sweeps = 100
    settings%fluid_density = density
    call resolved_hydrodynamics_create(provider, solver, system, settings, 'momentum', -1, case%stabilise, &
                                       restart=.false., gravity=gravity)
    call provider%prepare(solver, system)
    loads = particle_loads_zero(1)
    dt = case%viscous_number * solver%grid%dx**2 / viscosity
    slip_old = 0
    slip = 0
    do step = 1, case%max_steps
      call provider%fluid_step(solver, forcing, system, dt)
      do substep = 1, case%substeps
        call provider%loads(system, real(substep - 1, wp) / case%substeps, loads)
        call particle_system_step(system, dt / case%substeps, loads)
      end do
      u_face = global_sum(sum(solver%u(n, 1:n, 1:nz))) / real(n * n, wp)
      slip = system%bodies(1)%velocity(1) - u_face
      result%steps = step
      if (step > 50 .and. abs(slip - slip_old) <= case%steady_tolerance * abs(slip)) then
        result%steady = .true.
        exit
      end if
      slip_old = slip
    end do
    result%slip = slip
    result%drag_coefficient = weight / (6.0_wp * pi * density * viscosity * radius * slip)
    result%diameter_cells = 2.0_wp * radius / solver%grid%dx
    associate (status => provider%scene%ibm%geometry%component(1)%status)
      fluid_flux = global_sum(sum(solver%u(1:n, 1:n, 1:nz), mask=status(1:n, 1:n, 1:nz) == node_fluid))
    end associate
    result%momentum = (density * solver%grid%dx * solver%grid%dy * solver%grid%dz * fluid_flux &
                       + system%bodies(1)%mass * system%bodies(1)%velocity(1)) / (density * box**3 * slip)
    result%wall_seconds = wall_time() - t0
  end subroutine run_settling_sphere
end module settling_sphere_case
