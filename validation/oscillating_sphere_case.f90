!> The oscillating sphere (rung 8 of the validation ladder; docs/validation.md, "Moving bodies"): a
!> sphere in a periodic box of fluid at rest oscillates along x, c(t) = c0 + A sin(omega t), so that its surface crosses
!> grid nodes (nodes change status every few steps), and the x force by momentum balance is compared
!> with Stokes' (1851) solution for a sphere in translational oscillation, in the complex form of
!> Landau & Lifshitz, Fluid Mechanics, section 24, problem 5 (velocity U e^{i omega t}):
!>   F_S = -6 pi mu R U (1 + lambda R + lambda^2 R^2 / 9),   lambda = (1 + i) / delta,
!>   delta = sqrt(2 nu / omega) (the Stokes layer),
!> the steady drag, the Basset history force and the added mass (lambda^2 R^2/9 term: (1/2) rho V
!> i omega U). This is the surface force on the sphere, which is what the momentum balance gives
!> (the fictitious fluid's inertia is taken out of the load, docs/theory.md).
!>
!> Box correction: in the periodic box the fluid's mean velocity u_f follows the force,
!> rho (L^3 - V) du_f/dt = -F (the box's momentum), and the sphere sees the relative velocity U - u_f
!> and the ambient acceleration du_f/dt, whose pressure gradient adds rho V du_f/dt (Maxey & Riley
!> 1983, Phys. Fluids 26, 883, the fluid-acceleration term). With S = -F_S / U and M = rho (L^3 - V):
!>   F = -S U / (1 + S / (i omega M) + rho V / M).
!> The periodic images' flow beyond this mean motion is left out: it is O(phi) for the potential
!> (added-mass) part and screened beyond delta for the vortical part (delta = R here, L = 8 R).
!>
!> The motion starts at t0 = T/4 (velocity zero, the sphere at c0 + A) so that no impulsive start
!> feeds a long Basset transient; the force is fitted over the last period by
!> a cos(omega t) + b sin(omega t) + c (whole periods: the three are orthogonal over the samples),
!> F_hat = a - i b, attributed to the middle of each step. Spikes: the largest second difference
!> |F^{n+1} - 2 F^n + F^{n-1}| / 2 over the fitted period (a spike s at one step gives 2 s; the smooth
!> force gives |F_hat| (omega dt)^2), over |F_hat|.
module oscillating_sphere_case
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use wall_clock, only: wall_time
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: make_spheroid
  use immersed_boundary, only: ibm_settings_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  implicit none
  private
  public :: oscillating_sphere_case_t, oscillating_sphere_result_t, run_oscillating_sphere, stokes_oscillating_force

  type :: oscillating_sphere_case_t
    integer :: cells = 32                        !< cells per side of the box
    real(wp) :: diameter_cells = 8.0_wp          !< D / dx
    real(wp) :: layer_over_radius = 1.0_wp       !< delta / R: sets omega = 2 nu / delta^2
    real(wp) :: amplitude_cells = 0.5_wp         !< A / dx (A / R = 2 amplitude_cells / diameter_cells)
    real(wp) :: offset_cells(3) = [0.13_wp, 0.27_wp, 0.41_wp]   !< c0 - box centre, cells (no grid symmetry)
    real(wp) :: viscous_number = 0.06_wp         !< about nu dt / dx^2 (dt is then fitted to the period)
    integer :: periods = 3                       !< periods run; the last one is fitted
    character(len=16) :: coupling = 'implicit'
    character(len=16) :: pressure_scheme = 'incremental'
    logical :: extend_pressure = .true.          !< the sealed cells' pressure (immersed_boundary)
  end type oscillating_sphere_case_t

  type :: oscillating_sphere_result_t
    complex(wp) :: force = 0                     !< N, fitted F_hat
    complex(wp) :: reference = 0                 !< N, Stokes with the box correction
    complex(wp) :: unbounded = 0                 !< N, Stokes in the unbounded fluid
    real(wp) :: amplitude_error = 0              !< |F_hat| / |reference| - 1
    real(wp) :: phase_error = 0                  !< rad, arg(F_hat / reference)
    real(wp) :: largest_spike = 0                !< largest |F^{n+1} - 2 F^n + F^{n-1}| / 2 over |F_hat| (fitted period)
    real(wp) :: largest_residual = 0             !< largest |F - fit| over |F_hat| (fitted period)
    real(wp) :: jump_at_changes = 0, jump_otherwise = 0   !< the scene's load-jump report (whole run)
    integer :: uncovered = 0, covered = 0        !< nodes changing status over the run
    integer :: steps_per_period = 0
    real(wp) :: amplitude_over_radius = 0, reynolds = 0   !< A / R and U D / nu
    real(wp) :: wall_seconds = 0
  end type oscillating_sphere_result_t

  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp

contains

  !> Stokes' force on the sphere for velocity amplitude velocity (N, complex, e^{i omega t}), in the
  !> unbounded fluid (box = 0) or with the periodic box's mean-flow correction (module header).
  pure complex(wp) function stokes_oscillating_force(radius, omega, velocity, box_length) result(force)
    real(wp), intent(in) :: radius, omega, velocity, box_length
    complex(wp) :: lambda, s
    real(wp) :: volume, fluid_mass
    lambda = cmplx(1.0_wp, 1.0_wp, wp) * sqrt(omega / (2.0_wp * viscosity))
    s = 6.0_wp * pi * density * viscosity * radius * (1.0_wp + lambda * radius + lambda**2 * radius**2 / 9.0_wp)
    force = -s * velocity
    if (box_length > 0.0_wp) then
      volume = 4.0_wp / 3.0_wp * pi * radius**3
      fluid_mass = density * (box_length**3 - volume)
      force = force / (1.0_wp + s / (cmplx(0.0_wp, omega, wp) * fluid_mass) + density * volume / fluid_mass)
    end if
  end function stokes_oscillating_force

  !> Run the case (collective).
  subroutine run_oscillating_sphere(case, result)
    type(oscillating_sphere_case_t), intent(in) :: case
    type(oscillating_sphere_result_t), intent(out) :: result
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(1)
    type(ibm_settings_t) :: settings
    real(wp) :: h, radius, layer, omega, period, dt, amplitude, velocity, t0, t, a, b, c, phase
    real(wp), allocatable :: force(:)
    integer :: steps, step, n, first

    t0 = wall_time()
    grid_cfg = grid_config_t(nx=case%cells, ny=case%cells, nz=case%cells, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = 'explicit'
    fluid_cfg%pressure_scheme = case%pressure_scheme
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0

    h = solver%grid%dx
    radius = 0.5_wp * case%diameter_cells * h
    layer = case%layer_over_radius * radius
    omega = 2.0_wp * viscosity / layer**2
    period = 2.0_wp * pi / omega
    result%steps_per_period = ceiling(period / (case%viscous_number * h**2 / viscosity))
    dt = period / result%steps_per_period
    amplitude = case%amplitude_cells * h
    velocity = amplitude * omega
    result%amplitude_over_radius = amplitude / radius
    result%reynolds = velocity * 2.0_wp * radius / viscosity

    motion(1)%shape = make_spheroid('sphere', radius, density)
    motion(1)%centre = 0.5_wp * box + case%offset_cells * h
    motion(1)%amplitude = [amplitude, 0.0_wp, 0.0_wp]
    motion(1)%frequency = 1.0_wp / period
    settings%coupling = case%coupling
    settings%max_sweeps = 100
    settings%fluid_density = density
    solver%time = 0.25_wp * period
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings))
    scene%extend_pressure = case%extend_pressure

    steps = case%periods * result%steps_per_period
    allocate(force(0:steps))
    force(0) = 0
    do step = 1, steps
      call immersed_step(scene, solver, dt)
      force(step) = scene%force(1, 1)
    end do

    ! Fit over the last period; the load of step n belongs to the middle of the step.
    first = steps - result%steps_per_period + 1
    a = 0; b = 0; c = 0
    do n = first, steps
      t = 0.25_wp * period + (n - 0.5_wp) * dt
      a = a + force(n) * cos(omega * t)
      b = b + force(n) * sin(omega * t)
      c = c + force(n)
    end do
    a = 2.0_wp * a / result%steps_per_period
    b = 2.0_wp * b / result%steps_per_period
    c = c / result%steps_per_period
    result%force = cmplx(a, -b, wp)
    result%unbounded = stokes_oscillating_force(radius, omega, velocity, 0.0_wp)
    result%reference = stokes_oscillating_force(radius, omega, velocity, box)
    result%amplitude_error = abs(result%force) / abs(result%reference) - 1.0_wp
    phase = atan2(aimag(result%force / result%reference), real(result%force / result%reference))
    result%phase_error = phase
    do n = first, steps
      t = 0.25_wp * period + (n - 0.5_wp) * dt
      result%largest_residual = max(result%largest_residual, &
                                    abs(force(n) - (a * cos(omega * t) + b * sin(omega * t) + c)))
      result%largest_spike = max(result%largest_spike, 0.5_wp * abs(force(n) - 2.0_wp * force(n - 1) + force(n - 2)))
    end do
    result%largest_residual = result%largest_residual / abs(result%force)
    result%largest_spike = result%largest_spike / abs(result%force)
    result%jump_at_changes = scene%ibm%changes%largest_jump_changes
    result%jump_otherwise = scene%ibm%changes%largest_jump_steady
    result%uncovered = int(scene%ibm%changes%total_uncovered)
    result%covered = int(scene%ibm%changes%total_covered)
    result%wall_seconds = wall_time() - t0
  end subroutine run_oscillating_sphere
end module oscillating_sphere_case
