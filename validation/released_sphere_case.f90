!> The validation case of the release decay (docs/validation.md, "Free particles"): one free sphere,
!> resolved by the immersed boundary (module resolved_hydrodynamics, no gravity), started at U_0
!> along x in the periodic cube of fluid at rest (the injection sets the fluid inside the body to
!> its rigid motion), its velocity recorded after every fluid step, against the unsteady Stokes
!> decay of module unsteady_stokes: U(t) = U(0+) u(t), U(0+) = m U_0 / (m + m_f/2).
!> The velocity is the body's minus the box's mean fluid velocity far away, U_face (the flux through
!> the x-face at the box edge over its area), so that the box's drift (the total momentum m U_0 is
!> conserved and spreads over the box: the sphere tends to m U_0 / (m + m_f,box)) is taken out to
!> first order. Also recorded: the body's own velocity, and the box's momentum
!> rho_f dV sum_{fluid u nodes} u + m U_p over m U_0 (one if nothing is lost).
module released_sphere_case
  use agglo_kinds, only: wp
  use error_handling, only: fatal
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
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create, &
                                    resolved_hydrodynamics_options_t
  use unsteady_stokes, only: released_sphere_t, particle_response_time, released_start_velocity, release_decay_quadrature
  implicit none
  private
  public :: release_case_t, release_result_t, run_released_sphere, release_comparison_t, compare_release

  type :: release_case_t
    integer :: cells = 32                        !< cells per box edge
    real(wp) :: diameter_cells = 8               !< D / dx
    real(wp) :: density_ratio = 2.72_wp          !< rho_p / rho_f
    logical :: stabilise = .true.                !< the added-mass stabilisation
    integer :: substeps = 4                      !< particle sub-steps per fluid step
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2
    real(wp) :: response_times = 1               !< run time in units of tau_p = 2 rho_p a^2 / (9 mu)
    real(wp) :: offset_cells(3) = [0.13_wp, 0.27_wp, 0.41_wp]   !< sphere centre - box centre, cells
    !> &scene added_mass_history: the stabilisation's history estimate, the resolved viscous reaction
    !> one step late (module resolved_hydrodynamics, "History with explicit diffusion")
    logical :: history = .true.
    !> &fluid pressure_scheme: 'non_incremental' (the decks' default) or 'incremental' (its second
    !> step re-applies the start's impulsive pressure: docs/validation.md)
    character(len=16) :: pressure_scheme = 'non_incremental'
  end type release_case_t

  type :: release_result_t
    type(released_sphere_t) :: sphere              !< for the reference (module unsteady_stokes)
    real(wp) :: start_velocity = 0                 !< m/s, U_0
    real(wp) :: step = 0                           !< s, the fluid step
    real(wp) :: response_time = 0                  !< s, tau_p
    real(wp), allocatable :: slip(:)               !< (0:steps) U_p - U_face after each step, over U_0
    real(wp), allocatable :: velocity(:)           !< (0:steps) U_p over U_0
    real(wp) :: momentum = 0                       !< the box's momentum at the end over m U_0
    real(wp) :: reynolds = 0                       !< U_0 D / nu
    real(wp) :: wall_seconds = 0
  end type release_result_t

  !> The run against the reference U(0+) u(t) (module unsteady_stokes), all over U_0.
  type :: release_comparison_t
    integer :: steps = 0                           !< fluid steps within the run
    real(wp) :: first(3) = 0                       !< U_p / U_0 after steps 1, 2, 3
    real(wp) :: first_reference(3) = 0             !< the reference there
    real(wp) :: largest_difference = 0             !< max |U_p - U_ref| / U_0 over the run
    real(wp) :: largest_relative_late = 0          !< max |U_p / U_ref - 1| over t >= late tau_p
    real(wp) :: displacement_error = 0             !< int U_p dt / int U_ref dt - 1 over the run
    real(wp) :: final_relative = 0                 !< U_p / U_ref - 1 at the last step
  end type release_comparison_t

  ! Water-like units in a 1 mm cube; U_0 = 1e-6 m/s keeps U_0 D / nu below 1e-3.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, start_speed = 1.0e-6_wp

contains

  !> Run the release over case%response_times tau_p (collective).
  subroutine run_released_sphere(case, result)
    type(release_case_t), intent(in) :: case
    type(release_result_t), intent(out) :: result
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
    real(wp) :: radius, dt, u_face, fluid_flux, t0
    integer :: step, steps, substep, n, nz

    t0 = wall_time()
    n = case%cells
    if (.not. (case%diameter_cells > 0.0_wp .and. case%diameter_cells < 0.8_wp * n)) &
      call fatal('released_sphere_case: diameter_cells must lie in (0, 0.8 * case%cells), the sphere inside the box')
    grid_cfg = grid_config_t(nx=n, ny=n, nz=n, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = 'explicit'
    fluid_cfg%pressure_scheme = case%pressure_scheme
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    nz = solver%grid%nz_local
    radius = 0.5_wp * case%diameter_cells * solver%grid%dx
    shape(1) = make_spheroid('sphere', radius, case%density_ratio * density)
    call rigid_body_of_spheroid(body(1), shape(1), 0.5_wp * box + case%offset_cells * solver%grid%dx, &
                                [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [start_speed, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    models%integrator = integrator_euler
    call particle_system_create(system, shape, body, models, [box, box, box])
    call particle_system_interact(system, 1.0_wp)
    settings%coupling = 'implicit'
    settings%tolerance = 1.0e-12_wp
    settings%max_sweeps = 100
    settings%fluid_density = density
    call resolved_hydrodynamics_create(provider, solver, system, resolved_hydrodynamics_options_t(settings=settings, &
                                       stabilise=case%stabilise, explicit_history=case%history))
    call provider%prepare(solver, system)
    loads = particle_loads_zero(1)

    result%sphere = released_sphere_t(radius=radius, density=case%density_ratio * density, fluid_density=density, &
                                      viscosity=density * viscosity)
    result%start_velocity = start_speed
    result%response_time = particle_response_time(result%sphere)
    result%reynolds = start_speed * 2.0_wp * radius / viscosity
    dt = case%viscous_number * solver%grid%dx**2 / viscosity
    result%step = dt
    steps = ceiling(case%response_times * result%response_time / dt)
    allocate(result%slip(0:steps), result%velocity(0:steps))
    result%slip(0) = 1
    result%velocity(0) = 1
    do step = 1, steps
      call provider%fluid_step(solver, forcing, system, dt)
      do substep = 1, case%substeps
        call provider%loads(system, real(substep - 1, wp) / case%substeps, loads)
        call particle_system_step(system, dt / case%substeps, loads)
      end do
      u_face = global_sum(sum(solver%u(n, 1:n, 1:nz))) / real(n * n, wp)
      result%velocity(step) = system%bodies(1)%velocity(1) / start_speed
      result%slip(step) = (system%bodies(1)%velocity(1) - u_face) / start_speed
    end do
    associate (status => provider%scene%ibm%geometry%component(1)%status)
      fluid_flux = global_sum(sum(solver%u(1:n, 1:n, 1:nz), mask=status(1:n, 1:n, 1:nz) == node_fluid))
    end associate
    result%momentum = (density * solver%grid%dx * solver%grid%dy * solver%grid%dz * fluid_flux &
                       + system%bodies(1)%mass * system%bodies(1)%velocity(1)) / (system%bodies(1)%mass * start_speed)
    result%wall_seconds = wall_time() - t0
  end subroutine run_released_sphere

  !> The run against the reference, computed by product integration on the run's steps divided
  !> by refine; late: the start of the relative comparison in units of tau_p.
  subroutine compare_release(result, refine, late, comparison)
    type(release_result_t), intent(in) :: result
    integer, intent(in) :: refine
    real(wp), intent(in) :: late
    type(release_comparison_t), intent(out) :: comparison
    real(wp), allocatable :: decay(:), reference(:)
    real(wp) :: start, travelled, expected_travel
    integer :: n, steps
    steps = ubound(result%velocity, 1)
    comparison%steps = steps
    allocate(decay(0:steps * refine), reference(0:steps))
    call release_decay_quadrature(result%sphere, result%step / refine, decay)
    start = released_start_velocity(result%sphere, 1.0_wp)
    reference = start * decay(0:steps * refine:refine)
    reference(0) = 1   ! before the release's impulsive pressure: U_0
    comparison%first = result%velocity(1:3)
    comparison%first_reference = reference(1:3)
    travelled = 0
    expected_travel = 0
    do n = 1, steps
      comparison%largest_difference = max(comparison%largest_difference, abs(result%velocity(n) - reference(n)))
      if (n * result%step >= late * result%response_time) comparison%largest_relative_late = &
          max(comparison%largest_relative_late, abs(result%velocity(n) / reference(n) - 1))
      travelled = travelled + 0.5_wp * (result%velocity(n - 1) + result%velocity(n))
      expected_travel = expected_travel + 0.5_wp * (reference(n - 1) + reference(n))
    end do
    ! The first interval of the reference from U(0+), not from U_0 (the jump is instantaneous).
    expected_travel = expected_travel + 0.5_wp * (start - 1)
    travelled = travelled + 0.5_wp * (start - 1)
    comparison%displacement_error = travelled / expected_travel - 1
    comparison%final_relative = result%velocity(steps) / reference(steps) - 1
  end subroutine compare_release
end module released_sphere_case
