!> The squeeze-film validation case of the immersed boundary (docs/validation.md, "Lubrication"):
!> two equal spheres of radius a on a line along x approach each other, each at speed U, in fluid
!> initially at rest, in Stokes flow (Re = 2 U a / nu below 1e-4). The geometry is held fixed at a
!> given surface gap h (the rigid velocities +U and -U are imposed on a fixed placement) and the
!> flow is run to steady state: at Re << 1 the quasi-steady force of an approach at gap h.
!>
!> Reference: the exact force of two equal spheres approaching along their line of centres in
!> unbounded fluid, F = 6 pi mu a U beta, with Brenner's bispherical-coordinate series (Brenner
!> 1961, Chem. Eng. Sci. 16, 242, the sphere moving toward a free surface, which is the symmetry
!> plane of the pair):
!>   beta = (4/3) sinh(al) sum_{n>=1} n (n+1) / ((2n-1)(2n+3))
!>          [ (4 cosh^2((n+1/2) al) + (2n+1)^2 sinh^2(al)) / (2 sinh((2n+1) al) - (2n+1) sinh(2 al)) - 1 ],
!> cosh(al) = 1 + h / (2a). Near contact beta = 1/(2 eps) - (9/20) ln eps - (3/56) eps ln eps + 1.346
!> (eps = h/a; Cox & Brenner 1967; Jeffrey & Onishi 1984; Costa et al. 2015, who quote the constant 1.346), which
!> tests/unit/test_lubrication checks against the series.
!> The box is 2 n_y cells long along x and n_y = box_diameters D wide: the periodic images of the
!> pair (a force dipole) change the force by a few per cent at the widest gaps (the table says so).
!>
!> The free approach (run_free_squeeze): the same pair, free (&scene particle_coupling = 'resolved',
!> module resolved_hydrodynamics, the added-mass stabilisation on), pushed together from rest by
!> constant equal and opposite forces +-F along the line of centres, F = 6 pi mu a U_p (U_p the
!> speed of one isolated sphere under F), in fluid at rest; optionally with the sub-grid
!> lubrication of the particle system (module lubrication, hand-over h_out). Recorded every fluid
!> step: the gap, the approach speed U of each sphere, the resolved force along the line of centres
!> and the mean lubrication force of the sub-steps. Reference (approach_reference): the one-
!> dimensional motion of one sphere under F against Brenner's resistance,
!>   (m + m_a) dU/dt = F - 6 pi mu a beta(h) U,  dh/dt = -2 U,
!> m_a = rho_f V / 2 (the isolated sphere's added mass; it matters only in the start transient).
!> The push makes the approach quasi-steady (the gap closes a cell in many viscous times a^2/nu),
!> so U(h) tends to F / (6 pi mu a beta(h)).
!> The same free approach runs a needle pair tip to tip or a disk pair face to face (shape,
!> aspect_ratio; symmetry axes on the line of centres x, r the volume-equivalent radius, F = 6 pi mu
!> r U_p) in a box of box_cells cells; the history then carries each body's isolated axial Stokes
!> drag zeta (module stokes_resistance) and the reduced radius R_eff of the closest points (module
!> lubrication) for the curvature-scaled near-contact reference of module push_pair_case.
module squeeze_case
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use wall_clock, only: wall_time
  use error_handling, only: fatal
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: spheroid_t, make_spheroid
  use config_collision, only: default_lubrication_handover
  use immersed_boundary, only: ibm_settings_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  use forcing_driver, only: forcing_driver_t
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use quaternion, only: symmetry_axis
  use particle_system, only: particle_system_t, particle_models_t, particle_loads_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero, &
                             particle_system_set_added_inertia
  use lubrication, only: lubrication_model_t
  use stokes_resistance, only: spheroid_resistance_coefficients
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create, &
                                    resolved_hydrodynamics_options_t
  implicit none
  private
  public :: squeeze_case_t, squeeze_result_t, run_squeeze, brenner_squeeze_coefficient, squeeze_speed, &
            squeeze_dynamic_viscosity
  public :: free_squeeze_case_t, free_squeeze_history_t, run_free_squeeze, approach_reference, free_squeeze_sample
  public :: pushed_tips_case
  public :: squeeze_fluid, squeeze_hold_to_steady_state

  type :: squeeze_case_t
    real(wp) :: diameter_cells = 8.0_wp          !< D / dx
    real(wp) :: gap_cells = 2.0_wp               !< h / dx, surface gap
    integer :: width_cells = 32                  !< n_y = n_z; n_x = 2 n_y
    character(len=16) :: coupling = 'implicit'   !< immersed_boundary coupling
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2 (AB2 explicit diffusion: below 1/12)
    real(wp) :: steady_tolerance = 1.0e-7_wp     !< relative change of the force per step at steady state
    integer :: max_steps = 20000
    real(wp) :: offset_cells(3) = [0.31_wp, 0.13_wp, 0.27_wp]   !< gap centre - box centre, cells
    !> 'incremental' (the calibrated squeeze tables) or 'non_incremental' (the decks' default): flat
    !> faces a cell or less apart grow without bound with the incremental pressure only (docs/theory.md).
    character(len=16) :: pressure_scheme = 'incremental'
  end type squeeze_case_t

  type :: squeeze_result_t
    real(wp) :: force = 0                  !< N, resolved (F2_x - F1_x) / 2, > 0 resisting the approach
    real(wp) :: reference = 0              !< N, 6 pi mu a U beta (Brenner)
    real(wp) :: error = 0                  !< force / reference - 1
    real(wp) :: gap_over_radius = 0        !< eps = h / a
    real(wp) :: radius = 0                 !< m, a
    real(wp) :: cell = 0                   !< m, dx
    real(wp) :: reynolds = 0               !< 2 U a / nu
    integer :: steps = 0
    logical :: steady = .false.
    real(wp) :: wall_seconds = 0
  end type squeeze_result_t

  type :: free_squeeze_case_t
    character(len=8) :: shape = 'sphere'         !< 'sphere', 'needle' (tip to tip) or 'disk' (face to face)
    real(wp) :: aspect_ratio = 1.0_wp            !< needle a/b, disk b/a (module spheroid); unused for a sphere
    real(wp) :: diameter_cells = 8.0_wp          !< D / dx; needle, disk: the volume-equivalent 2 r / dx
    integer :: width_cells = 32                  !< n_y = n_z; n_x = 2 n_y (when box_cells is unset)
    integer :: box_cells(3) = 0                  !< n_x, n_y, n_z; all 0: 2 width_cells, width_cells, width_cells
    real(wp) :: start_gap_cells = 5.0_wp         !< h / dx at the start (both spheres at rest)
    real(wp) :: stop_gap_cells = 0.05_wp         !< the run ends when the gap falls below this
    real(wp) :: push_reynolds = 0.1_wp           !< U_p a / nu (F = 6 pi mu a U_p)
    real(wp) :: density_ratio = 2.72_wp          !< rho_p / rho_f
    integer :: substeps = 4                      !< particle sub-steps per fluid step
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2
    logical :: lubrication = .false.             !< the sub-grid lubrication of the particle system
    real(wp) :: handover_cells = 1.0_wp          !< h_out / dx
    integer :: max_steps = 40000
    integer :: max_sweeps = 1000                 !< ghost-row sweeps (near contact they rise to about 90)
    real(wp) :: offset_cells(3) = [0.31_wp, 0.13_wp, 0.27_wp]   !< gap centre - box centre, cells
    !> &fluid pressure_scheme: 'incremental' (the table of the incremental scheme) or 'non_incremental'
    !> (the decks' default; docs/validation.md, "The decks' pressure scheme")
    character(len=16) :: pressure_scheme = 'incremental'
  end type free_squeeze_case_t

  !> One row per fluid step (allocated to the steps taken).
  type :: free_squeeze_history_t
    real(wp), allocatable :: time(:)          !< s, end of the fluid step
    real(wp), allocatable :: gap(:)           !< m, surface gap at the end of the step
    real(wp), allocatable :: speed(:)         !< m/s, U = (U_1x - U_2x) / 2 imposed in the step (start)
    real(wp), allocatable :: resolved(:)      !< N, (F_2x - F_1x) / 2 of the immersed boundary, > 0 resisting
    real(wp), allocatable :: lubrication(:)   !< N, the same of the sub-grid lubrication, mean over the sub-steps
    real(wp) :: push = 0                      !< N, F
    real(wp) :: radius = 0                    !< m, a (needle, disk: the volume-equivalent r)
    real(wp) :: cell = 0                      !< m, dx
    real(wp) :: mass = 0                      !< kg, m
    real(wp) :: added_mass = 0                !< kg, rho_f V / 2 (a sphere's)
    real(wp) :: axial_drag = 0                !< N s/m, zeta: one isolated body's Stokes drag along x
    real(wp) :: reduced_radius = 0            !< m, R_eff of the closest points (the last step the model acted)
    real(wp) :: lateral_offset = 0            !< m, distance of the two centres across x at the end
    real(wp) :: tilt = 0                      !< rad, the larger angle of a symmetry axis to x at the end
    integer :: steps = 0
    integer :: max_sweeps_seen = 0            !< most ghost-row sweeps of one imposition
    logical :: reached = .false.              !< the gap fell below stop_gap_cells
    real(wp) :: wall_seconds = 0
  end type free_squeeze_history_t

  ! Water-like units; U a / nu = 1e-5 at D/dx = 8 on a 1 mm box.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, speed = 1.0e-7_wp
  real(wp), parameter :: squeeze_speed = speed                            !< m/s, U of each sphere
  real(wp), parameter :: squeeze_dynamic_viscosity = density * viscosity  !< Pa s, mu

contains

  !> The free approach of a needle pair tip to tip or a disk pair face to face (module header):
  !> the thin dimension (needle minor axis, disk thickness) thin_cells cells, box box_cells, 1 mm
  !> along x, U_p r / nu = push_reynolds, from rest start_gap_cells apart until the gap falls below
  !> stop_gap (m), with the sub-grid lubrication at the hand-over of the decks' pressure-free
  !> projection (with the incremental pressure two flat faces within about a cell grow without
  !> bound, docs/theory.md). The pair sits on the grid's mirror planes across x: an offset across x
  !> seeds the sliding of a face-to-face pair (the common normal tilts by the offset over the faces'
  !> radius of curvature), which grows over the long squeeze of the disks.
  function pushed_tips_case(shape, aspect_ratio, thin_cells, box_cells, push_reynolds, start_gap_cells, stop_gap) &
      result(case)
    character(len=*), intent(in) :: shape
    real(wp), intent(in) :: aspect_ratio, thin_cells, push_reynolds, start_gap_cells, stop_gap
    integer, intent(in) :: box_cells(3)
    type(free_squeeze_case_t) :: case
    type(spheroid_t) :: unit
    case%shape = shape
    case%aspect_ratio = aspect_ratio
    ! 2 r / dx from the thin dimension: 2 min(a, b) of the volume-equivalent radius 1 is thin / (2 r / dx).
    unit = make_spheroid(trim(shape), 1.0_wp, 1.0_wp, aspect_ratio)
    case%diameter_cells = thin_cells / min(unit%a, unit%b)
    case%box_cells = box_cells
    case%offset_cells(2:3) = 0
    case%start_gap_cells = start_gap_cells
    case%push_reynolds = push_reynolds
    case%lubrication = .true.
    case%pressure_scheme = 'non_incremental'
    case%handover_cells = default_lubrication_handover('resolved', 'resolved', case%pressure_scheme, 1.0_wp, 1.0_wp)
    case%max_steps = 400000
    case%stop_gap_cells = stop_gap / (box / box_cells(1))
  end function pushed_tips_case

  !> Brenner's beta (module header) for two equal spheres at gap h / a = gap_over_radius > 0, summed
  !> until a term is below 1e-15 of the sum.
  pure real(wp) function brenner_squeeze_coefficient(gap_over_radius) result(beta)
    real(wp), intent(in) :: gap_over_radius
    real(wp) :: alpha, k, term, total
    integer :: n
    alpha = acosh(1.0_wp + 0.5_wp * gap_over_radius)
    total = 0
    do n = 1, 1000000
      k = 2.0_wp * n + 1.0_wp
      term = real(n, wp) * (n + 1) / ((2.0_wp * n - 1.0_wp) * (2.0_wp * n + 3.0_wp)) &
             * ((4.0_wp * cosh(0.5_wp * k * alpha)**2 + (k * sinh(alpha))**2) &
                / (2.0_wp * sinh(k * alpha) - k * sinh(2.0_wp * alpha)) - 1.0_wp)
      total = total + term
      if (abs(term) < 1.0e-15_wp * abs(total) .or. k * alpha > 700.0_wp) exit
    end do
    beta = 4.0_wp / 3.0_wp * sinh(alpha) * total
  end function brenner_squeeze_coefficient

  !> The fluid of the squeeze cases at rest: cells(1) x cells(2) x cells(3) cells, the x length the
  !> 1 mm box, lengths (m) the three box lengths (cubic cells); explicit diffusion, pressure_scheme
  !> (fluid_solver) when present, else the incremental pressure.
  subroutine squeeze_fluid(cells, solver, lengths, pressure_scheme)
    integer, intent(in) :: cells(3)
    type(fluid_solver_t), intent(out) :: solver
    real(wp), intent(out) :: lengths(3)
    character(len=*), intent(in), optional :: pressure_scheme
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    lengths = box * real(cells, wp) / cells(1)
    grid_cfg = grid_config_t(nx=cells(1), ny=cells(2), nz=cells(3), length_x=lengths(1), length_y=lengths(2), &
                             length_z=lengths(3))
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = 'explicit'
    fluid_cfg%pressure_scheme = 'incremental'
    if (present(pressure_scheme)) fluid_cfg%pressure_scheme = pressure_scheme
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
  end subroutine squeeze_fluid

  !> Run the case at one gap to steady state (collective).
  subroutine run_squeeze(case, result)
    type(squeeze_case_t), intent(in) :: case
    type(squeeze_result_t), intent(out) :: result
    type(fluid_solver_t) :: solver
    type(prescribed_motion_t) :: motion(2)
    real(wp) :: h, radius, gap, t0, lengths(3)
    integer :: n

    t0 = wall_time()
    call squeeze_fluid([2 * case%width_cells, case%width_cells, case%width_cells], solver, lengths, &
                       case%pressure_scheme)

    h = solver%grid%dx
    radius = 0.5_wp * case%diameter_cells * h
    gap = case%gap_cells * h
    do n = 1, 2
      motion(n)%shape = make_spheroid('sphere', radius, density)
      motion(n)%centre = 0.5_wp * lengths + case%offset_cells * h
      motion(n)%centre(1) = motion(n)%centre(1) + (2 * n - 3) * (radius + 0.5_wp * gap)
      motion(n)%velocity = [(3 - 2 * n) * speed, 0.0_wp, 0.0_wp]   ! body 1 along +x, body 2 along -x
    end do
    call squeeze_hold_to_steady_state(case, solver, motion, result)
    result%gap_over_radius = gap / radius
    result%radius = radius
    result%reference = 6.0_wp * pi * density * viscosity * radius * speed &
                       * brenner_squeeze_coefficient(result%gap_over_radius)
    result%error = result%force / result%reference - 1.0_wp
    result%reynolds = 2.0_wp * speed * radius / viscosity
    result%wall_seconds = wall_time() - t0
  end subroutine run_squeeze

  !> The fixed-placement run of every prescribed squeeze case: the two bodies of motion (shape,
  !> orientation, velocity; centre = the placement to hold) moving at their rigid velocities on a
  !> placement held fixed, the flow of the fresh solver run to steady state (relative change of the
  !> force below case%steady_tolerance per step; coupling, nu dt/dx^2 and the step limit from case).
  !> Sets result%force = (F_2x - F_1x) / 2 (> 0 resisting an approach along x), steps, steady and
  !> cell (collective).
  subroutine squeeze_hold_to_steady_state(case, solver, motion, result)
    type(squeeze_case_t), intent(in) :: case
    type(fluid_solver_t), intent(inout) :: solver
    type(prescribed_motion_t), intent(in) :: motion(2)
    type(squeeze_result_t), intent(inout) :: result
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: held(2)
    type(ibm_settings_t) :: settings
    real(wp) :: h, dt, force_old, force_new
    integer :: step

    h = solver%grid%dx
    held = motion
    settings%coupling = case%coupling
    settings%max_sweeps = 100
    settings%fluid_density = density
    dt = case%viscous_number * h**2 / viscosity
    call hold_in_place(solver%time + dt)
    call immersed_scene_create(scene, solver, held, immersed_scene_options_t(settings=settings))

    force_old = 0
    force_new = 0
    do step = 1, case%max_steps
      ! The placement of the step is c0 + U t at its end time: hold it at the fixed centres.
      call hold_in_place(solver%time + dt)
      scene%motion = held
      call immersed_step(scene, solver, dt)
      force_new = 0.5_wp * (scene%force(1, 2) - scene%force(1, 1))
      result%steps = step
      if (step > 10 .and. abs(force_new - force_old) <= case%steady_tolerance * abs(force_new)) then
        result%steady = .true.
        exit
      end if
      force_old = force_new
    end do
    result%force = force_new
    result%cell = h

  contains

    !> Set each body's c0 so that c0 + U time is its fixed centre.
    subroutine hold_in_place(time)
      real(wp), intent(in) :: time
      integer :: m
      do m = 1, 2
        held(m)%centre = motion(m)%centre - motion(m)%velocity * time
      end do
    end subroutine hold_in_place
  end subroutine squeeze_hold_to_steady_state

  !> The free approach (module header) from rest at start_gap_cells until the gap is below
  !> stop_gap_cells or max_steps fluid steps (collective).
  subroutine run_free_squeeze(case, history)
    type(free_squeeze_case_t), intent(in) :: case
    type(free_squeeze_history_t), intent(out) :: history
    type(fluid_solver_t) :: solver
    type(forcing_driver_t) :: forcing                  ! inactive
    type(spheroid_t) :: shapes(2)
    type(rigid_body_t) :: bodies(2)
    type(particle_models_t) :: models
    type(particle_system_t) :: system
    type(particle_loads_t) :: loads
    type(ibm_settings_t) :: settings
    type(resolved_hydrodynamics_t) :: provider
    real(wp) :: h, radius, gap, dt, t0, centre(3), lubrication_sum, lengths(3), coefficients(4), axis(3)
    real(wp), allocatable :: rows(:, :)
    integer :: step, substep, n, cells(3)
    character(len=64) :: text

    t0 = wall_time()
    select case (trim(case%shape))
    case ('sphere', 'needle', 'disk')
    case default
      call fatal('free squeeze: shape '''//trim(case%shape)//''' is not allowed; allowed: sphere, needle, disk')
    end select
    cells = case%box_cells
    if (all(cells == 0)) cells = [2 * case%width_cells, case%width_cells, case%width_cells]
    if (any(cells < 1)) then
      write(text, '(3(1x,i0))') cells
      call fatal('free squeeze: box_cells ='//trim(text)//'; each must be >= 1 (or all 0 for the width_cells box)')
    end if
    call squeeze_fluid(cells, solver, lengths, case%pressure_scheme)

    h = solver%grid%dx
    radius = 0.5_wp * case%diameter_cells * h
    gap = case%start_gap_cells * h
    centre = [0.5_wp * box, 0.5_wp * lengths(2), 0.5_wp * lengths(3)] + case%offset_cells * h
    do n = 1, 2
      if (case%shape == 'sphere') then
        shapes(n) = make_spheroid('sphere', radius, case%density_ratio * density)
      else
        shapes(n) = make_spheroid(trim(case%shape), radius, case%density_ratio * density, case%aspect_ratio)
      end if
      ! The symmetry axis (semi-axis a) along x: the closest points are the tips or face centres.
      call rigid_body_of_spheroid(bodies(n), shapes(n), centre + [(2 * n - 3) * (shapes(n)%a + 0.5_wp * gap), 0.0_wp, 0.0_wp], &
                                  [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp], [0.0_wp, 0.0_wp, 0.0_wp])
    end do
    models%integrator = integrator_euler
    models%lubrication = case%lubrication
    ! The roughness far below every gap of the run: the model's force is not saturated.
    models%lubrication_model = lubrication_model_t(dynamic_viscosity=density * viscosity, &
                                                   outer_gap=case%handover_cells * h, roughness=1.0e-6_wp * h)
    call particle_system_create(system, shapes, bodies, models, [box, lengths(2), lengths(3)])
    dt = case%viscous_number * h**2 / viscosity
    call particle_system_interact(system, dt / case%substeps)

    settings%coupling = 'implicit'
    settings%tolerance = 1.0e-12_wp
    settings%max_sweeps = case%max_sweeps
    settings%fluid_density = density
    call resolved_hydrodynamics_create(provider, solver, system, resolved_hydrodynamics_options_t(settings=settings))
    ! The push as the provider's constant external force per body (its net-weight slot): it enters
    ! the added-mass update like a weight, and sums to zero over the pair, so the box needs no drive.
    history%push = 6.0_wp * pi * density * viscosity * radius * (case%push_reynolds * viscosity / radius)   ! U_p
    provider%weight(:, 1) = [history%push, 0.0_wp, 0.0_wp]
    provider%weight(:, 2) = [-history%push, 0.0_wp, 0.0_wp]
    call provider%prepare(solver, system)
    loads = particle_loads_zero(2)

    allocate(rows(5, case%max_steps))   ! time, gap, speed, resolved, lubrication
    do step = 1, case%max_steps
      rows(3, step) = 0.5_wp * (system%bodies(1)%velocity(1) - system%bodies(2)%velocity(1))
      call provider%fluid_step(solver, forcing, system, dt)
      call particle_system_set_added_inertia(system, provider%impulse_inertia(system))
      history%max_sweeps_seen = max(history%max_sweeps_seen, provider%scene%predicted%sweeps)
      lubrication_sum = 0
      do substep = 1, case%substeps
        call provider%loads(system, real(substep - 1, wp) / case%substeps, loads)
        call particle_system_step(system, dt / case%substeps, loads)
        lubrication_sum = lubrication_sum + 0.5_wp * (system%lubrication_loads%force(1, 2) &
                                                      - system%lubrication_loads%force(1, 1))
        if (system%pairs(1)%lubrication%active) history%reduced_radius = system%pairs(1)%lubrication%geometry%reduced_radius
      end do
      if (.not. system%pairs(1)%active) call fatal('free squeeze: the pair''s closest points are not current')
      rows(1, step) = solver%time
      rows(2, step) = system%pairs(1)%contact%gap
      rows(4, step) = 0.5_wp * (provider%force(1, 2) - provider%force(1, 1))
      rows(5, step) = lubrication_sum / case%substeps
      history%steps = step
      if (rows(2, step) < case%stop_gap_cells * h) then
        history%reached = .true.
        exit
      end if
    end do
    history%time = rows(1, 1:history%steps)
    history%gap = rows(2, 1:history%steps)
    history%speed = rows(3, 1:history%steps)
    history%resolved = rows(4, 1:history%steps)
    history%lubrication = rows(5, 1:history%steps)
    history%radius = radius
    history%cell = h
    history%mass = system%bodies(1)%mass
    history%added_mass = 0.5_wp * density * shapes(1)%volume
    coefficients = spheroid_resistance_coefficients(shapes(1)%a, shapes(1)%b)
    history%axial_drag = 6.0_wp * pi * density * viscosity * radius * coefficients(1)
    history%lateral_offset = norm2(system%bodies(2)%position(2:3) - system%bodies(1)%position(2:3))
    do n = 1, 2
      axis = symmetry_axis(system%bodies(n)%quaternion)
      history%tilt = max(history%tilt, acos(min(1.0_wp, abs(axis(1)))))
    end do
    history%wall_seconds = wall_time() - t0
  end subroutine run_free_squeeze

  !> A history's values where its gap first falls to gap (m), linear between the two fluid steps
  !> around it; the last value if it never does.
  pure real(wp) function free_squeeze_sample(history, values, gap) result(value)
    type(free_squeeze_history_t), intent(in) :: history
    real(wp), intent(in) :: values(:), gap
    integer :: s
    value = values(size(values))
    do s = 2, size(values)
      if (history%gap(s) <= gap) then
        value = values(s - 1) + (gap - history%gap(s - 1)) / (history%gap(s) - history%gap(s - 1)) &
                * (values(s) - values(s - 1))
        return
      end if
    end do
  end function free_squeeze_sample

  !> The reference approach (module header) of one sphere of mass + added mass inertia under the
  !> push: speed (m/s) and time (s) at which the gap first reaches each of gaps(:) (m, decreasing),
  !> from rest at start_gap (m). Classical RK4 with the step a fiftieth of the local response time
  !> (m + m_a) / (6 pi mu a beta), which near contact shrinks with the gap.
  subroutine approach_reference(push, radius, inertia, start_gap, gaps, speed, time)
    real(wp), intent(in) :: push, radius, inertia, start_gap, gaps(:)
    real(wp), intent(out) :: speed(:), time(:)
    real(wp) :: state(2), k(2, 4), step, t, previous(2), fraction, drag
    integer :: next
    drag = 6.0_wp * pi * density * viscosity * radius
    state = [start_gap, 0.0_wp]   ! gap, U
    t = 0
    next = 1
    do while (next <= size(gaps))
      step = 0.02_wp * inertia / (drag * brenner_squeeze_coefficient(state(1) / radius))
      previous = state
      k(:, 1) = rate(state)
      k(:, 2) = rate(state + 0.5_wp * step * k(:, 1))
      k(:, 3) = rate(state + 0.5_wp * step * k(:, 2))
      k(:, 4) = rate(state + step * k(:, 3))
      state = state + step / 6.0_wp * (k(:, 1) + 2.0_wp * k(:, 2) + 2.0_wp * k(:, 3) + k(:, 4))
      t = t + step
      do while (next <= size(gaps))
        if (state(1) > gaps(next)) exit
        ! Linear within the step (its gap change is a small fraction of the gap).
        fraction = (previous(1) - gaps(next)) / (previous(1) - state(1))
        speed(next) = previous(2) + fraction * (state(2) - previous(2))
        time(next) = t - step + fraction * step
        next = next + 1
      end do
    end do

  contains

    function rate(y) result(dydt)
      real(wp), intent(in) :: y(2)
      real(wp) :: dydt(2)
      dydt = [-2.0_wp * y(2), (push - drag * brenner_squeeze_coefficient(y(1) / radius) * y(2)) / inertia]
    end function rate
  end subroutine approach_reference
end module squeeze_case
