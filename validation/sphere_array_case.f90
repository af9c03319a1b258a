!> The validation case of the immersed boundary: one sphere in the periodic cube, i.e. a simple-cubic
!> array of spheres, in Stokes flow driven by a uniform body force f (a mean pressure gradient) over
!> the whole box, run to steady state (docs/validation.md, "Immersed boundary").
!>
!> Drag coefficient K = F / (6 pi mu a U) with F = f L^3 the force per sphere (the drive over the
!> whole cell, solid included) and U the superficial velocity, the flux through a cell face over its
!> area (Zick & Homsy 1982, J. Fluid Mech. 115, 13, Table 2: K = 2.810 at phi = 0.064, 4.292 at
!> phi = 0.125). U is measured on the x-face plane at the box edge, which the
!> sphere (diameter below the box) never cuts.
!> Steady state: the relative change of U per step below steady_tolerance. With aitken_window > 0
!> (translation only) the run stops earlier: the slowest mode of a dilute array is the spin-up of
!> the mean flow against the body's drag, a single exponential of time constant about
!> rho L^3 / (6 pi mu r c) (5000 steps at 32^3 for the needles of the ladder), far slower than the
!> diffusive modes. Once those have decayed, Aitken's delta-squared on U sampled every window
!> steps, U_inf = U3 - (U3 - U2)^2 / ((U3 - U2) - (U2 - U1)), removes it; the run stops when two
!> successive estimates agree to aitken_tolerance, and U (and the loads, which follow U
!> quasi-steadily) are scaled to U_inf.
!>
!> With rotating = .true. the sphere instead turns at Omega about z in fluid without drive, and the
!> result is the steady torque, to compare with 8 pi mu a^3 Omega (Stokes, unbounded) after the
!> box-size extrapolation (the periodic images' correction falls as (a/L)^3).
!>
!> shape = 'needle' or 'disk' (aspect 5) places a spheroid of volume-equivalent radius radius_cells
!> with its symmetry axis along `axis` (lab frame), driven along x (translation) or turning about
!> rotation_axis (rotating). The geometry stays frozen at the initial orientation (no
!> reclassification; the rigid velocity Omega x r is imposed on it): the torque is the
!> instantaneous Stokes resistance of that orientation (Omega r = 1e-7 m/s would turn the body by
!> only about 1e-3 rad over a run anyway).
!>
!> box_cells = (nx, ny, nz) makes the box non-cubic at the spacing dx = 1 mm / cells (the tight
!> boxes of the spheroid symmetry check: the body's torque while translating along a principal axis
!> vanishes by symmetry in any periodic lattice of it); the drive's force is then f Lx Ly Lz.
module sphere_array_case
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: global_sum
  use wall_clock, only: wall_time
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: make_spheroid
  use icosphere_mesh, only: build_icosphere_mesh
  use quaternion, only: quaternion_from_axis_angle
  use immersed_boundary, only: ibm_settings_t
  use hypre_solver, only: linear_solver_config_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  implicit none
  private
  public :: sphere_array_case_t, sphere_array_result_t, run_sphere_array, fit_power_series

  type :: sphere_array_case_t
    integer :: cells = 13                        !< cells per box edge (dx = 1 mm / cells)
    integer :: box_cells(3) = 0                  !< a non-cubic box of these cells at that dx (0: cells^3)
    real(wp) :: volume_fraction = 0.125_wp       !< phi = V_sphere / L^3
    character(len=16) :: coupling = 'implicit'   !< immersed_boundary coupling
    real(wp) :: viscous_number = 0.06_wp         !< nu dt / dx^2 (AB2 explicit diffusion: below 1/12)
    real(wp) :: steady_tolerance = 1.0e-9_wp     !< relative change of U per step at steady state
    integer :: max_steps = 20000
    real(wp) :: offset_cells(3) = [0.13_wp, 0.27_wp, 0.41_wp]   !< sphere centre - box centre, cells
    real(wp) :: ghost_tolerance = 1.0e-12_wp
    logical :: rotating = .false.                !< rotating sphere, no drive, steady torque
    integer :: mesh_level = -1                   !< ghost nodes see the icosphere of this level ('mesh'); -1 analytic
    integer :: surface_level = -1                !< icosphere level of the face-sum loads; -1 none (momentum only)
    character(len=16) :: viscous_scheme = 'explicit'   !< or 'crank_nicolson' (the predictor with the body rows)
    type(linear_solver_config_t) :: predictor = linear_solver_config_t(method='bicgstab', preconditioner='user', &
                                                                       tolerance=1.0e-8_wp, max_iterations=200)
    character(len=8) :: shape = 'sphere'         !< 'sphere', or 'needle' / 'disk' of aspect 5
    real(wp) :: radius_cells = 0                 !< volume-equivalent radius in cells (0: from volume_fraction)
    real(wp) :: axis(3) = [1.0_wp, 0.0_wp, 0.0_wp]            !< symmetry axis in the lab frame
    real(wp) :: rotation_axis(3) = [0.0_wp, 0.0_wp, 1.0_wp]   !< direction of Omega (rotating)
    integer :: aitken_window = 0                 !< steps between the samples of U (0: run to steady)
    real(wp) :: aitken_tolerance = 1.0e-6_wp     !< relative change of successive Aitken estimates
    integer :: history_every = 0                 !< record U and the torques every this many steps (0: none)
  end type sphere_array_case_t

  type :: sphere_array_result_t
    real(wp) :: drag_coefficient = 0       !< K
    real(wp) :: diameter_cells = 0         !< D / dx
    real(wp) :: superficial_velocity = 0   !< m/s
    real(wp) :: force(3) = 0               !< N, momentum-balance load of the last step
    real(wp) :: drive(3) = 0               !< N, f L^3 (f Lx Ly Lz in a non-cubic box)
    real(wp) :: torque(3) = 0              !< N m, momentum-balance torque of the last step
    real(wp) :: surface_force(3) = 0       !< N, face-sum load of the last step (immersed_surface_loads)
    real(wp) :: surface_torque(3) = 0      !< N m, face-sum torque of the last step
    real(wp) :: stokes_torque = 0          !< N m, 8 pi mu a^3 Omega (rotating case)
    real(wp) :: radius_over_box = 0        !< a / L (r / L for a spheroid, r volume-equivalent; L = cells dx)
    real(wp) :: radius = 0                 !< m, a (r)
    real(wp) :: angular_speed = 0          !< rad/s, |Omega| (rotating)
    real(wp) :: dynamic_viscosity = 0      !< Pa s
    integer :: steps = 0
    logical :: steady = .false.
    logical :: extrapolated = .false.      !< stopped by the Aitken estimate (U and loads scaled to it)
    integer :: max_sweeps = 0              !< most sweeps of an imposition on u*
    real(wp) :: mean_sweeps = 0            !< mean sweeps per imposition on u*
    real(wp) :: slip = 0                   !< last re-imposition's largest change / velocity scale
    real(wp) :: divergence = 0             !< 1/s, cut-cell divergence after the last re-imposition
    real(wp) :: wall_seconds = 0
    !> (8, samples): step, U (m/s), momentum torque (3, N m), face-sum torque (3, N m), every
    !> history_every steps: the torque's approach to steady state (the translating body's torque
    !> follows U quasi-steadily once the diffusive modes have decayed, so T/U settles before U does)
    real(wp), allocatable :: history(:, :)
  end type sphere_array_result_t

  ! Water-like units, a 1 mm cell; the drive makes U about 1e-7 m/s: Re = U D / nu below 1e-4.
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, drive = 2.5e-3_wp

contains

  !> Run the case to steady state (collective).
  subroutine run_sphere_array(case, result)
    type(sphere_array_case_t), intent(in) :: case
    type(sphere_array_result_t), intent(out) :: result
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(1)
    type(ibm_settings_t) :: settings
    real(wp) :: radius, dt, u_old, u_new, t0, sweeps_total, drive_x, axis(3), turn(3)
    real(wp) :: samples(3), estimate, previous_estimate, scale, lengths(3), force_drive
    integer :: step, counts(3), samples_recorded

    t0 = wall_time()
    counts = case%cells
    if (any(case%box_cells > 0) .and. .not. all(case%box_cells > 0)) &
      error stop 'sphere_array_case: box_cells needs three positive counts (or all 0 for a cubic box)'
    if (all(case%box_cells > 0)) counts = case%box_cells
    lengths = counts * (box / case%cells)
    grid_cfg = grid_config_t(nx=counts(1), ny=counts(2), nz=counts(3), length_x=lengths(1), length_y=lengths(2), &
                             length_z=lengths(3))
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = case%viscous_scheme
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0

    radius = (3.0_wp * case%volume_fraction / (4.0_wp * pi))**(1.0_wp / 3.0_wp) * box
    if (case%radius_cells > 0) radius = case%radius_cells * solver%grid%dx
    motion(1)%shape = make_spheroid(trim(case%shape), radius, density)
    ! Body x (the symmetry axis) onto `axis`: the rotation about e_x x axis.
    axis = case%axis / norm2(case%axis)
    turn = [0.0_wp, -axis(3), axis(2)]
    if (norm2(turn) > 1.0e-12_wp) motion(1)%orientation = quaternion_from_axis_angle(turn / norm2(turn), &
                                                                                  acos(max(-1.0_wp, min(1.0_wp, axis(1)))))
    motion(1)%centre = 0.5_wp * lengths + case%offset_cells * solver%grid%dx
    if (case%mesh_level >= 0) call build_icosphere_mesh(motion(1)%shape, case%mesh_level, motion(1)%mesh)
    settings%coupling = case%coupling
    settings%tolerance = case%ghost_tolerance
    settings%max_sweeps = 100
    settings%fluid_density = density
    drive_x = drive
    if (case%rotating) then
      drive_x = 0
      ! Omega a = 1e-7 m/s: Re = Omega a^2 / nu below 1e-4.
      motion(1)%angular_velocity = case%rotation_axis / norm2(case%rotation_axis) * 1.0e-7_wp / radius
    end if
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, &
                               driving_force=[drive_x, 0.0_wp, 0.0_wp], surface_level=case%surface_level, &
                               predictor_config=case%predictor))
    ! The centre never moves; a turning spheroid keeps its initial classification (frozen geometry).
    scene%moving = .false.

    dt = case%viscous_number * solver%grid%dx**2 / viscosity
    u_old = 0
    sweeps_total = 0
    samples = 0
    previous_estimate = 0
    scale = 1
    samples_recorded = 0
    if (case%history_every > 0) allocate(result%history(8, case%max_steps / case%history_every))
    do step = 1, case%max_steps
      call immersed_step(scene, solver, dt)
      result%max_sweeps = max(result%max_sweeps, scene%predicted%sweeps)
      sweeps_total = sweeps_total + scene%predicted%sweeps
      if (case%rotating) then
        u_new = dot_product(scene%torque(:, 1), case%rotation_axis) / norm2(case%rotation_axis)
      else
        u_new = global_sum(sum(solver%u(solver%grid%nx, 1:solver%grid%ny, 1:solver%grid%nz_local))) / &
                real(solver%grid%ny * solver%grid%nz, wp)
      end if
      result%steps = step
      if (case%history_every > 0) then
        if (mod(step, case%history_every) == 0) then
          samples_recorded = samples_recorded + 1
          result%history(:, samples_recorded) = [real(step, wp), global_sum(sum(solver%u(solver%grid%nx, &
              1:solver%grid%ny, 1:solver%grid%nz_local))) / real(solver%grid%ny * solver%grid%nz, wp), &
              scene%torque(:, 1), scene%surface_torque(:, 1)]
        end if
      end if
      if (step > 10 .and. abs(u_new - u_old) <= case%steady_tolerance * abs(u_new)) then
        result%steady = .true.
        exit
      end if
      u_old = u_new
      if (case%aitken_window > 0 .and. .not. case%rotating .and. mod(step, max(case%aitken_window, 1)) == 0) then
        samples = [samples(2), samples(3), u_new]
        if (step >= 3 * case%aitken_window .and. abs((samples(3) - samples(2)) - (samples(2) - samples(1))) > 0) then
          estimate = samples(3) - (samples(3) - samples(2))**2 / ((samples(3) - samples(2)) - (samples(2) - samples(1)))
          if (step >= 4 * case%aitken_window .and. &
              abs(estimate - previous_estimate) <= case%aitken_tolerance * abs(estimate)) then
            result%steady = .true.
            result%extrapolated = .true.
            scale = estimate / u_new
            u_new = estimate
            exit
          end if
          previous_estimate = estimate
        end if
      end if
    end do
    result%torque = scale * scene%torque(:, 1)
    result%stokes_torque = 8.0_wp * pi * density * viscosity * radius**3 * motion(1)%angular_velocity(3)
    result%radius = radius
    result%angular_speed = norm2(motion(1)%angular_velocity)
    result%dynamic_viscosity = density * viscosity
    result%radius_over_box = radius / box
    result%superficial_velocity = u_new
    result%diameter_cells = 2.0_wp * radius / solver%grid%dx
    force_drive = drive * product(lengths)
    result%drive = [force_drive, 0.0_wp, 0.0_wp]
    result%drag_coefficient = force_drive / (6.0_wp * pi * density * viscosity * radius * u_new)
    result%force = scale * scene%force(:, 1)
    result%surface_force = scale * scene%surface_force(:, 1)
    result%surface_torque = scale * scene%surface_torque(:, 1)
    result%mean_sweeps = sweeps_total / result%steps
    result%slip = scene%projected%largest_change
    result%divergence = scene%divergence
    result%wall_seconds = wall_time() - t0
    if (case%history_every > 0) result%history = result%history(:, :samples_recorded)
  end subroutine run_sphere_array

  !> Least-squares fit of y = sum_k coefficients(k) x**powers(k) through the samples (x, y), at least
  !> as many as powers: the box-size series of a periodic array's resistance in r/L (docs/validation.md,
  !> rung 6). Normal equations with the columns scaled by their largest value, Gaussian elimination
  !> with partial pivoting.
  subroutine fit_power_series(x, y, powers, coefficients)
    real(wp), intent(in) :: x(:), y(:), powers(:)
    real(wp), intent(out) :: coefficients(:)
    real(wp) :: design(size(x), size(powers)), normal(size(powers), size(powers)), rhs(size(powers))
    real(wp) :: scales(size(powers)), row(size(powers)), factor, swap
    integer :: k, j, pivot, n
    n = size(powers)
    if (size(x) < n .or. size(y) /= size(x) .or. size(coefficients) /= n) &
      error stop 'fit_power_series: need size(x) = size(y) >= size(powers) = size(coefficients)'
    do k = 1, n
      design(:, k) = x**powers(k)
      scales(k) = maxval(abs(design(:, k)))
      if (scales(k) <= 0) scales(k) = 1
      design(:, k) = design(:, k) / scales(k)
    end do
    normal = matmul(transpose(design), design)
    rhs = matmul(transpose(design), y)
    do k = 1, n
      pivot = k - 1 + maxloc(abs(normal(k:, k)), dim=1)
      row = normal(k, :); normal(k, :) = normal(pivot, :); normal(pivot, :) = row
      swap = rhs(k); rhs(k) = rhs(pivot); rhs(pivot) = swap
      if (abs(normal(k, k)) <= 0) error stop 'fit_power_series: singular (repeated x or too few distinct samples)'
      do j = k + 1, n
        factor = normal(j, k) / normal(k, k)
        normal(j, k:) = normal(j, k:) - factor * normal(k, k:)
        rhs(j) = rhs(j) - factor * rhs(k)
      end do
    end do
    do k = n, 1, -1
      coefficients(k) = (rhs(k) - dot_product(normal(k, k + 1:), coefficients(k + 1:))) / normal(k, k)
    end do
    coefficients = coefficients / scales
  end subroutine fit_power_series
end module sphere_array_case
