!> &scene particle_coupling = 'resolved': the hydrodynamic-load provider of the scene loop
!> (module particle_hydrodynamics) for free particles resolved by the immersed boundary (docs/theory.md,
!> "Free particles"; docs/design.md, "The pair in the resolved fluid").
!>
!> Fluid step t^n -> t^{n+1}: the bodies are placed where the particle state predicts them at
!> t^{n+1} (centre x^n + U^n dt, orientation turned by Omega^n dt) and move with the state's U^n,
!> Omega^n, the latest known velocities; the immersed scene's staged step (immersed_step_placed) imposes
!> them and returns the momentum-balance force and torque F^n, T^n. The placement error is
!> O(a dt^2) (docs/theory.md, "Free particles"); the one-step lag of the velocities is what the
!> added-mass stabilisation below is about. The loads stay frozen over the fluid step's
!> particle_substeps sub-steps (closest points, DLVO and collisions every sub-step).
!>
!> Added mass (&scene added_mass = .true.): a lagged load holds the fluid's reaction to the last
!> change of the imposed velocity, F_a ~ -M_a (U^n - U^{n-1}) / dt, which fed back explicitly
!> amplifies a velocity disturbance by -M_a / m per step (unstable for the face-on disk, M_a / m =
!> 1.11 at the calcite density ratio 2.72). With the body-frame potential-flow tensors M_a =
!> rho_f V diag(k_ax, k_tr, k_tr) and I_a = diag(0, i_tr, i_tr) (Lamb 1932 sec. 373), the update
!> solves, per body axis,
!>   (m + M_a) dU/dt = F^n + M_a A^n + F_other,   A^n = (U^n - U^{n-1}) / dt,
!>   (I + I_a) dOmega/dt = T^n + I_a Alpha^n + T_other,
!> i.e. the same added-mass estimate is put back into the lagged load and taken implicitly, so
!> only the difference between the resolved reaction and its estimate is explicit. The load handed
!> to the particle step is m dU/dt - F_other (I dOmega/dt - T_other), so that the explicit step,
!> which divides by m (I), moves the body with that acceleration (as point_particle_coupling does).
!> A contact impulse is a load too: the particle system applies it with the same m + M_a (I + I_a)
!> (resolved_impulse_inertia; module rigid_body, "Impulses in a fluid"). With the body's mass alone,
!> the impulse that holds a body against its attraction F_other would be m / (m + M_a) of the
!> attraction's; two bodies whose M_a along the normal differ cannot both be held by one equal and
!> opposite impulse, and the held pair drifts under the difference (docs/theory.md, "Contact
!> impulses with the added mass").
!>
!> Long fluid steps (&fluid viscous_scheme = 'crank_nicolson'; docs/theory.md, "Crank-Nicolson with
!> free particles"): the ghost and interior rows of the predictor's system (immersed_predictor) hold
!> the same lagged U^n, Omega^n at t^{n+1} as the explicit path's imposition, so the added-mass
!> estimate stays consistent; the bodies are reclassified every step as there. At nu dt/dx^2 of
!> order 1 and above the fluid's reaction to a velocity change within one step is no longer the
!> potential-flow added mass alone: the Stokes drag C dt and the history (Basset) reaction, whose
!> impulse over the first step is C L 2 sqrt(dt / (pi nu)) (L = a for a sphere: 6 pi mu a^2 /
!> sqrt(pi nu t) integrated; for rotation a / 3), grow with dt and reach the body's own mass (the
!> settling sphere at nu dt/dx^2 = 10 diverged with M_a alone). The estimate M becomes, per body
!> axis, M_a + C dt + M_B with M_B = C L 2 sqrt(dt / (pi nu)) (C, L from the spheroid's Stokes
!> resistance, stokes_resistance), taken implicitly as above; and because a velocity change keeps
!> reacting through its history in later steps (the Basset weights w_j = sqrt(j + 1) - sqrt(j) of a
!> change j steps back), what that tail will put into the next step's load is taken out of the
!> put-back (function put_back; history_steps steps remembered, the oldest change leaving with its
!> whole remaining weight so that the put-back weights sum to M and the box's momentum closes).
!> With explicit diffusion C and L are zero and the step is the added-mass one above unchanged.
!> Sub-steps: the particle sub-steps of a long fluid step integrate the frozen load as before; the
!> placement x^n + U^n dt differs from the particles' x^{n+1} by a dt^2 / 2, and after a collision
!> within the step by up to the velocity jump times dt / 2; the next step places the bodies where
!> the particles are.
!>
!> History with explicit diffusion (&scene added_mass_history; docs/theory.md, "History with explicit
!> diffusion"): the explicit predictor diffuses u^n, which does not yet hold the velocity the step
!> imposes, so the resolved viscous reaction to a velocity change starts one fluid step after it
!> (the added mass within the step, the sqrt(t) history one step late; measured in docs/theory.md,
!> "History with explicit diffusion"). Then the
!> estimate is M = M_a + M_B (the drag stays with the resolved load, history_lag = 1) and the
!> put-back weighs the resolved history of a change j steps back with w_{j-1} instead of w_j
!> (function put_back). The start's jump from the fluid at rest, which the injection leaves to the
!> first step's resolved load, and the change of the second step are remembered for the whole run.
!>
!> Gravity (&pair gravity, g): each body feels its net weight W = (rho_p - rho_f) V g as a
!> constant external force (added to the loads), and the whole box (fluid and bodies' nodes) the
!> uniform drive -sum W / L^3, the mean pressure gradient beyond the hydrostatic one that keeps the
!> box's total momentum from growing (a settling suspension in a periodic box; the drive's share on
!> each body, -V sum W / L^3, arrives through the momentum-balance load).
!>
!> State across fluid steps: the velocities imposed in the last step (for A^n), the earlier
!> A^{n-j} (Crank-Nicolson's history estimate) and the loads; all go into the checkpoint
!> (resolved_write_checkpoint), the geometry is recomputed from the particle state every step.
module resolved_hydrodynamics
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use physical_constants, only: pi
  use logger, only: log_line
  use text_format, only: real_text, int_text
  use sample_statistics, only: median
  use checkpoint_files, only: checkpoint_t
  use run_directory, only: run_file
  use hdf5_files, only: h5_exists
  use hdf5_datasets, only: h5_read_scalar, h5_write_array, h5_read_array
  use fluid_solver, only: fluid_solver_t
  use forcing_driver, only: forcing_driver_t, forcing_driver_evaluate, forcing_driver_advance
  use particle_system, only: particle_system_t, particle_loads_t
  use quaternion, only: rotation_matrix, quaternion_from_axis_angle, quaternion_product, quaternion_normalise
  use spheroid, only: spheroid_t
  use icosphere_mesh, only: icosphere_mesh_t, build_icosphere_mesh
  use stokes_resistance, only: spheroid_added_mass_coefficients, stokes_resistance_t, stokes_resistance_of
  use immersed_geometry, only: immersed_body_t
  use immersed_boundary, only: ibm_settings_t, imposition_report_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use immersed_diagnostics, only: ibm_fallback_rows
  use immersed_scene, only: immersed_scene_t, immersed_scene_options_t, prescribed_motion_t, immersed_scene_create, &
                            immersed_step_placed, loads_open, loads_write, loads_close
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  use rigid_body, only: angular_velocity_lab, added_inertia_t
  use hypre_solver, only: linear_solver_config_t
  use added_mass_estimate, only: lagged_reaction, put_back
  implicit none
  private
  public :: resolved_hydrodynamics_t, resolved_hydrodynamics_options_t, resolved_hydrodynamics_create, &
            rotational_added_inertia

  !> How the provider is built (resolved_hydrodynamics_create).
  type :: resolved_hydrodynamics_options_t
    !> The imposition (&scene ibm_coupling, &bodies ghost_tolerance, max_sweeps; the fluid density)
    type(ibm_settings_t) :: settings
    !> The loads handed on, as immersed_scene_create takes them (&bodies load_method): 'momentum' | 'surface'
    character(len=16) :: load_method = 'momentum'
    !> The face sum's icosphere level (&bodies mesh_level with load_method = 'surface' or
    !> compare_loads); -1: no face sum
    integer :: surface_level = -1
    logical :: stabilise = .true.                  !< the added-mass stabilisation (&scene added_mass)
    logical :: restart = .false.                   !< the fluid already holds the bodies (a restart)
    real(wp) :: gravity(3) = 0                     !< m/s^2 (module header, "Gravity")
    !> The hypre solve of the Crank-Nicolson predictor with the body rows (&fluid predictor_tolerance,
    !> predictor_max_iterations; unused with explicit diffusion)
    type(linear_solver_config_t) :: predictor_config = linear_solver_config_t(method='bicgstab', &
        preconditioner='user', tolerance=1.0e-8_wp, max_iterations=200)
    !> &bodies geometry = 'mesh': the icosphere level of the surface the ghost nodes see (20 4^level
    !> faces, inside the spheroid); -1: the analytic spheroid
    integer :: geometry_level = -1
    logical :: explicit_history = .false.          !< &scene added_mass_history (explicit diffusion only)
  end type resolved_hydrodynamics_options_t

  !> Fluid steps of velocity changes the history reaction's estimate remembers (Crank-Nicolson).
  integer, parameter :: history_steps = 32

  type, extends(particle_hydrodynamics_t) :: resolved_hydrodynamics_t
    type(immersed_scene_t) :: scene
    logical :: stabilise = .true.                      !< the added-mass stabilisation (&scene added_mass)
    logical :: inject = .true.                         !< set the fluid inside the bodies to their motion (a start)
    real(wp) :: box(3) = 0                             !< m, the periodic box
    real(wp) :: dt = 0                                 !< s, the last fluid step (0 before the first)
    real(wp), allocatable :: force(:, :), torque(:, :)          !< (3, n) N, N m: F^n, T^n of the last step (lab)
    real(wp), allocatable :: added_mass(:, :)                   !< (3, n) kg, body frame
    real(wp), allocatable :: weight(:, :)                       !< (3, n) N, net weight (rho_p - rho_f) V g (lab)
    real(wp), allocatable :: added_inertia(:, :)                !< (3, n) kg m^2, body frame
    !> (3, n) body frame, with Crank-Nicolson only (zero with explicit diffusion): the Stokes
    !> resistances C (N s/m, N m s) and the lengths L (m) of the one-step history reaction in the
    !> lagged-reaction estimate (module header, "Long fluid steps")
    real(wp), allocatable :: translational_resistance(:, :), rotational_resistance(:, :)
    real(wp), allocatable :: translational_history_length(:, :), rotational_history_length(:, :)
    real(wp) :: viscosity = 0                          !< m^2/s, kinematic
    !> Steps by which the resolved viscous reaction to a velocity change trails the change: 0 with
    !> Crank-Nicolson, 1 with explicit diffusion and the history estimate (&scene added_mass_history;
    !> module header, "History with explicit diffusion"); the estimate's weights follow it.
    integer :: history_lag = 0
    !> (3, n) lab: the velocities at the injection, the start's jump from the fluid at rest, and the
    !> change imposed in the second step, both remembered for the whole run (module header; zero
    !> without the history estimate with explicit diffusion, and after a restart from an older checkpoint)
    real(wp), allocatable :: start_velocity(:, :), start_angular_velocity(:, :)
    real(wp), allocatable :: start_change(:, :), start_angular_change(:, :)
    integer :: steps_since_start = 0                   !< fluid steps since the injection
    type(icosphere_mesh_t), allocatable :: meshes(:)   !< &bodies geometry = 'mesh': each body's (body frame)
    real(wp), allocatable :: imposed_velocity(:, :), imposed_angular_velocity(:, :)   !< (3, n) lab, last step
    real(wp), allocatable :: acceleration(:, :), angular_acceleration(:, :)           !< (3, n) lab, A^n, Alpha^n
    !> (3, n, history_steps) lab: A^{n-1}, A^{n-2}, ... (and Alpha), the history reaction's past (Crank-Nicolson)
    real(wp), allocatable :: earlier_acceleration(:, :, :), earlier_angular_acceleration(:, :, :)
    !> Ghost rows over all ranks with the image point moved back to the mid-gap (another body near)
    !> and, among them, the saturated Couette rows (gap below half a cell; immersed_geometry): the
    !> last step's counts and the most in one step
    integer :: fallbacks = 0, saturated = 0, most_fallbacks = 0, most_saturated = 0
  contains
    procedure :: prepare => resolved_prepare
    procedure :: fluid_step => resolved_fluid_step
    procedure :: loads => resolved_loads
    procedure :: write_checkpoint => resolved_write_checkpoint
    procedure :: read_checkpoint => resolved_read_checkpoint
    procedure :: log_progress => resolved_log_progress
    procedure :: open_outputs => resolved_open_outputs
    procedure :: record_fluid_step => resolved_record_fluid_step
    procedure :: finish => resolved_finish
    procedure :: impulse_inertia => resolved_impulse_inertia
  end type resolved_hydrodynamics_t

contains

  !> The provider for the system's bodies in the solver's fluid (collective: classifies the grid),
  !> as the options say (resolved_hydrodynamics_options_t).
  subroutine resolved_hydrodynamics_create(provider, solver, system, options)
    type(resolved_hydrodynamics_t), intent(out) :: provider
    type(fluid_solver_t), intent(inout) :: solver
    type(particle_system_t), intent(in) :: system
    type(resolved_hydrodynamics_options_t), intent(in) :: options
    type(prescribed_motion_t), allocatable :: motion(:)
    type(immersed_scene_options_t) :: scene_options
    real(wp) :: k(2), fluid_mass, ratio_translation, ratio_rotation
    type(stokes_resistance_t) :: resistance
    integer :: i
    provider%box = [solver%grid%lx, solver%grid%ly, solver%grid%lz]
    allocate(motion(system%n))
    allocate(provider%added_mass(3, system%n), provider%added_inertia(3, system%n), provider%weight(3, system%n))
    allocate(provider%translational_resistance(3, system%n), provider%rotational_resistance(3, system%n))
    allocate(provider%translational_history_length(3, system%n), provider%rotational_history_length(3, system%n))
    provider%translational_resistance = 0
    provider%rotational_resistance = 0
    provider%translational_history_length = provider%translational_resistance
    provider%rotational_history_length = provider%translational_resistance
    provider%viscosity = solver%viscosity
    provider%history_lag = 0
    if (options%explicit_history .and. .not. solver%crank_nicolson) provider%history_lag = 1
    ratio_translation = 0
    ratio_rotation = 0
    if (options%geometry_level >= 0) allocate(provider%meshes(system%n))
    do i = 1, system%n
      ! At rest where the particle is: the scene's first placement; every step places the bodies anew.
      motion(i)%shape = system%shapes(i)
      motion(i)%centre = system%bodies(i)%position
      motion(i)%orientation = system%bodies(i)%quaternion
      if (allocated(provider%meshes)) then
        call build_icosphere_mesh(system%shapes(i), options%geometry_level, provider%meshes(i))
        motion(i)%mesh = provider%meshes(i)
      end if
      fluid_mass = solver%density * system%shapes(i)%volume
      provider%weight(:, i) = (system%bodies(i)%mass - fluid_mass) * options%gravity
      k = spheroid_added_mass_coefficients(system%shapes(i)%a, system%shapes(i)%b)
      provider%added_mass(:, i) = fluid_mass * [k(1), k(2), k(2)]
      provider%added_inertia(:, i) = [0.0_wp, 1.0_wp, 1.0_wp] * &
                                     rotational_added_inertia(system%shapes(i), solver%density)
      if (solver%crank_nicolson .or. provider%history_lag > 0) then
        resistance = stokes_resistance_of(system%shapes(i), solver%density * solver%viscosity)
        provider%translational_resistance(:, i) = resistance%translational
        provider%rotational_resistance(:, i) = resistance%rotational
        ! The sphere's lengths a (Basset) and a / 3 (the rotating sphere's boundary layer), from the
        ! resistances' equivalent radii C / (6 pi mu) and (C_r / (8 pi mu))^(1/3) for a spheroid.
        provider%translational_history_length(:, i) = resistance%translational / (6.0_wp * pi * resistance%dynamic_viscosity)
        provider%rotational_history_length(:, i) = (resistance%rotational / (8.0_wp * pi * resistance%dynamic_viscosity)) &
                                                   **(1.0_wp / 3.0_wp) / 3.0_wp
      end if
      ratio_translation = max(ratio_translation, maxval(provider%added_mass(:, i)) / system%bodies(i)%mass)
      ratio_rotation = max(ratio_rotation, maxval(provider%added_inertia(:, i) / system%bodies(i)%inertia_body))
    end do
    scene_options%settings = options%settings
    scene_options%driving_force = -sum(provider%weight, dim=2) / (provider%box(1) * provider%box(2) * provider%box(3))
    scene_options%load_method = options%load_method
    scene_options%surface_level = options%surface_level
    scene_options%predictor_config = options%predictor_config
    call immersed_scene_create(provider%scene, solver, motion, scene_options)
    allocate(provider%force(3, system%n), provider%torque(3, system%n))
    provider%force = 0
    provider%torque = 0
    provider%imposed_velocity = provider%force
    provider%imposed_angular_velocity = provider%force
    provider%acceleration = provider%force
    provider%angular_acceleration = provider%force
    allocate(provider%start_velocity(3, system%n), provider%start_angular_velocity(3, system%n), &
             provider%start_change(3, system%n), provider%start_angular_change(3, system%n))
    provider%start_velocity = 0
    provider%start_angular_velocity = 0
    provider%start_change = provider%start_velocity
    provider%start_angular_change = provider%start_velocity
    allocate(provider%earlier_acceleration(3, system%n, history_steps), &
             provider%earlier_angular_acceleration(3, system%n, history_steps))
    provider%earlier_acceleration = 0
    provider%earlier_angular_acceleration = 0
    provider%stabilise = options%stabilise
    provider%inject = .not. options%restart
    call log_line('resolved particles: largest added mass / mass '//real_text(ratio_translation)// &
        ', added inertia / inertia '//real_text(ratio_rotation)//' (potential flow); added-mass stabilisation '// &
        merge('on ', 'off', options%stabilise))
    if (.not. options%stabilise .and. max(ratio_translation, ratio_rotation) >= 1.0_wp) call log_line('resolved particles: '// &
        'warning: an added mass or inertia above the body''s own with the stabilisation off: the lagged loads '// &
        'amplify a disturbance by that ratio per fluid step (unstable; &scene added_mass = .true.)')
    if (solver%crank_nicolson .and. options%stabilise) call log_line('resolved particles: Crank-Nicolson: the '// &
        'stabilisation''s estimate adds the Stokes drag C dt and the history reaction C L 2 sqrt(dt / (pi nu)) '// &
        'over the last '//int_text(history_steps)//' fluid steps (docs/theory.md)')
    if (provider%history_lag > 0 .and. options%stabilise) call log_line('resolved particles: explicit diffusion: the '// &
        'stabilisation''s estimate adds the history reaction C L 2 sqrt(dt / (pi nu)), the resolved one arriving one '// &
        'fluid step later (&scene added_mass_history; docs/theory.md)')
    if (solver%crank_nicolson .and. .not. options%stabilise) call log_line('resolved particles: warning: Crank-Nicolson '// &
        'without the stabilisation: at long steps the lagged drag and history reaction can exceed the body''s mass '// &
        '(unstable; &scene added_mass = .true.)')
  end subroutine resolved_hydrodynamics_create

  !> Rotational added inertia (kg m^2) of a spheroid about a transverse axis in potential flow
  !> (Lamb 1932 sec. 373, rotation about y of the ellipsoid (a, b, b)):
  !>   i_tr = rho_f V (b^2 - a^2)^2 (alpha0_ax - alpha0_tr) / (5 [2 (b^2 - a^2) + (b^2 + a^2) (alpha0_tr - alpha0_ax)]),
  !> alpha0 = 2 k / (1 + k) from the translational coefficients k; zero for a sphere. About the
  !> symmetry axis a spheroid displaces no fluid as it turns: zero.
  pure real(wp) function rotational_added_inertia(shape, fluid_density) result(inertia)
    type(spheroid_t), intent(in) :: shape
    real(wp), intent(in) :: fluid_density
    real(wp) :: k(2), alpha0(2), difference
    k = spheroid_added_mass_coefficients(shape%a, shape%b)
    alpha0 = 2.0_wp * k / (1.0_wp + k)
    difference = shape%b**2 - shape%a**2
    inertia = 0.0_wp
    if (abs(difference) <= 1.0e-8_wp * shape%b**2) return
    inertia = fluid_density * shape%volume * difference**2 * (alpha0(1) - alpha0(2)) &
              / (5.0_wp * (2.0_wp * difference + (shape%b**2 + shape%a**2) * (alpha0(2) - alpha0(1))))
  end function rotational_added_inertia

  !> At a start, the fluid inside each body (and its ghost rows) takes the body's rigid motion (the
  !> paper's injection); the imposed velocities start as the bodies' own (no change to react to).
  subroutine resolved_prepare(self, solver, system)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver
    type(particle_system_t), intent(in) :: system
    type(immersed_body_t), allocatable :: bodies(:)
    type(imposition_report_t) :: report
    if (.not. self%inject) return
    call current_bodies(self, system, 0.0_wp, bodies)
    call ibm_set_bodies(self%scene%ibm, solver%grid, bodies, self%imposed_velocity, self%imposed_angular_velocity, &
                        classify=.true.)
    call ibm_impose(self%scene%ibm, solver%grid, solver%u, solver%v, solver%w, report)
    self%inject = .false.
    self%steps_since_start = 0
    if (self%history_lag > 0) then
      self%start_velocity = self%imposed_velocity
      self%start_angular_velocity = self%imposed_angular_velocity
    end if
  end subroutine resolved_prepare

  subroutine resolved_fluid_step(self, solver, forcing, system, dt)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver
    type(forcing_driver_t), intent(inout) :: forcing
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dt
    type(immersed_body_t), allocatable :: bodies(:)
    real(wp) :: previous(3, system%n), previous_angular(3, system%n)
    previous = self%imposed_velocity
    previous_angular = self%imposed_angular_velocity
    call current_bodies(self, system, dt, bodies)
    if (forcing%active) then
      call forcing_driver_evaluate(forcing)
      call immersed_step_placed(self%scene, solver, dt, bodies, self%imposed_velocity, self%imposed_angular_velocity, &
                                forcing%fx, forcing%fy, forcing%fz)
      call forcing_driver_advance(forcing, dt)
    else
      call immersed_step_placed(self%scene, solver, dt, bodies, self%imposed_velocity, self%imposed_angular_velocity)
    end if
    self%force = self%scene%force
    self%torque = self%scene%torque
    self%dt = dt
    call ibm_fallback_rows(self%scene%ibm, self%fallbacks, self%saturated)
    self%most_fallbacks = max(self%most_fallbacks, self%fallbacks)
    self%most_saturated = max(self%most_saturated, self%saturated)
    self%earlier_acceleration = eoshift(self%earlier_acceleration, shift=-1, boundary=0.0_wp, dim=3)
    self%earlier_acceleration(:, :, 1) = self%acceleration
    self%earlier_angular_acceleration = eoshift(self%earlier_angular_acceleration, shift=-1, boundary=0.0_wp, dim=3)
    self%earlier_angular_acceleration(:, :, 1) = self%angular_acceleration
    self%acceleration = (self%imposed_velocity - previous) / dt
    self%angular_acceleration = (self%imposed_angular_velocity - previous_angular) / dt
    self%steps_since_start = self%steps_since_start + 1
    if (self%history_lag > 0 .and. self%steps_since_start == 2) then
      ! The start's first change leaves the memory of changes for the start's own (put_back).
      self%start_change = self%imposed_velocity - previous
      self%start_angular_change = self%imposed_angular_velocity - previous_angular
      self%acceleration = 0
      self%angular_acceleration = 0
    end if
  end subroutine resolved_fluid_step

  !> The bodies of the system's state carried ahead by lead (s) at their current velocities, and
  !> those velocities in imposed_velocity, imposed_angular_velocity (lab).
  subroutine current_bodies(self, system, lead, bodies)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: lead
    type(immersed_body_t), allocatable, intent(out) :: bodies(:)
    real(wp) :: omega(3)
    integer :: i
    allocate(bodies(system%n))
    do i = 1, system%n
      omega = angular_velocity_lab(system%bodies(i))
      bodies(i)%shape = system%shapes(i)
      if (allocated(self%meshes)) bodies(i)%mesh = self%meshes(i)
      bodies(i)%centre = modulo(system%bodies(i)%position + lead * system%bodies(i)%velocity, self%box)
      bodies(i)%orientation = quaternion_normalise(quaternion_product( &
          quaternion_from_axis_angle(omega, norm2(omega) * lead), system%bodies(i)%quaternion))
      self%imposed_velocity(:, i) = system%bodies(i)%velocity
      self%imposed_angular_velocity(:, i) = omega
    end do
  end subroutine current_bodies

  !> The last fluid step's loads, with the added-mass stabilisation (module header) when on.
  subroutine resolved_loads(self, system, theta, loads)
    class(resolved_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
    real(wp) :: rotation(3, 3), total(3), estimate(3), rate(3), lagged(3), history(3)
    integer :: i
    if (.not. (theta >= 0.0_wp .and. theta <= 1.0_wp)) call fatal('resolved particles: loads at theta outside [0, 1]')
    do i = 1, system%n
      if (.not. self%stabilise) then
        loads%force(:, i) = self%force(:, i) + self%weight(:, i)
        loads%torque(:, i) = self%torque(:, i)
        cycle
      end if
      rotation = rotation_matrix(system%bodies(i)%quaternion)
      associate (body => system%bodies(i), other_force => system%dlvo_loads%force(:, i), &
                 other_torque => system%dlvo_loads%torque(:, i))
        ! Body frame: (m + M) a = F + E + F_other with M = M_a + C dt + M_B and its put-back E (M_a and
        ! M_a A with explicit diffusion); the load is m a - F_other.
        total = matmul(self%force(:, i) + self%weight(:, i) + other_force, rotation)
        call lagged_reaction(self%added_mass(:, i), self%translational_resistance(:, i), &
                             self%translational_history_length(:, i), self%dt, self%viscosity, self%history_lag, &
                             lagged, history)
        estimate = put_back(lagged, history, self%acceleration(:, i), self%earlier_acceleration(:, i, :), rotation, &
                            self%history_lag, start_rate(self%start_velocity(:, i)), start_rate(self%start_change(:, i)), &
                            self%steps_since_start)
        rate = (total + estimate) / (body%mass + lagged)
        loads%force(:, i) = body%mass * matmul(rotation, rate) - other_force   ! the weight included
        total = matmul(self%torque(:, i) + other_torque, rotation)
        call lagged_reaction(self%added_inertia(:, i), self%rotational_resistance(:, i), &
                             self%rotational_history_length(:, i), self%dt, self%viscosity, self%history_lag, &
                             lagged, history)
        estimate = put_back(lagged, history, self%angular_acceleration(:, i), &
                            self%earlier_angular_acceleration(:, i, :), rotation, self%history_lag, &
                            start_rate(self%start_angular_velocity(:, i)), start_rate(self%start_angular_change(:, i)), &
                            self%steps_since_start)
        rate = (total + estimate) / (body%inertia_body + lagged)
        loads%torque(:, i) = matmul(rotation, body%inertia_body * rate) - other_torque
      end associate
    end do
  contains
    !> The start's jump from the fluid at rest as a rate over the step (1/s times the velocity).
    pure function start_rate(velocity) result(rate)
      real(wp), intent(in) :: velocity(3)
      real(wp) :: rate(3)
      rate = 0
      if (self%dt > 0.0_wp) rate = velocity / self%dt   ! no step yet: no start term (put_back)
    end function start_rate
  end subroutine resolved_loads

  !> With the stabilisation the loads move each body with m + M (I + I_a + ...), M the lagged
  !> reaction's estimate of the last step (lagged_reaction); its contact impulses carry the same.
  function resolved_impulse_inertia(self, system) result(added)
    class(resolved_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    type(added_inertia_t), allocatable :: added(:)
    real(wp) :: history(3)
    integer :: i
    allocate(added(system%n))
    if (.not. self%stabilise) return
    do i = 1, system%n
      call lagged_reaction(self%added_mass(:, i), self%translational_resistance(:, i), &
                           self%translational_history_length(:, i), self%dt, self%viscosity, self%history_lag, &
                           added(i)%mass, history)
      call lagged_reaction(self%added_inertia(:, i), self%rotational_resistance(:, i), &
                           self%rotational_history_length(:, i), self%dt, self%viscosity, self%history_lag, &
                           added(i)%inertia, history)
    end do
  end function resolved_impulse_inertia

  !> The last step's ghost-row sweeps (near contact the two bodies' rows couple and need more) and
  !> the bodies' force magnitudes, in the progress log: each body's up to listed_forces bodies, else
  !> the largest (with its body) and the median, so that a suspension's line stays readable.
  subroutine resolved_log_progress(self, solver)
    class(resolved_hydrodynamics_t), intent(in) :: self
    type(fluid_solver_t), intent(in) :: solver
    integer, parameter :: listed_forces = 8
    character(len=:), allocatable :: text
    real(wp) :: magnitudes(size(self%force, 2))
    integer :: i
    text = '  immersed boundary: sweeps '//int_text(self%scene%predicted%sweeps)//', residual '// &
           real_text(self%scene%predicted%residual)
    do i = 1, size(magnitudes)
      magnitudes(i) = norm2(self%force(:, i))
    end do
    if (size(magnitudes) <= listed_forces) then
      text = text//', |F| ='
      do i = 1, size(magnitudes)
        text = text//' '//real_text(magnitudes(i))
      end do
    else
      text = text//', |F| largest '//real_text(maxval(magnitudes))//' (body '//int_text(maxloc(magnitudes, 1))// &
             '), median '//real_text(median(magnitudes))
    end if
    text = text//' N, fallback rows '//int_text(self%fallbacks)//' (saturated '//int_text(self%saturated)// &
           '; most '//int_text(self%most_fallbacks)//', '//int_text(self%most_saturated)//')'
    call log_line(text)
  end subroutine resolved_log_progress

  !> bodies_loads.dat in the run directory: the immersed boundary's own force and torque on each
  !> body after every fluid step (before the added-mass stabilisation; docs/outputs.md).
  subroutine resolved_open_outputs(self, append, last_step)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    logical, intent(in) :: append
    integer(i8), intent(in) :: last_step
    call loads_open(self%scene, run_file('bodies_loads.dat'), append=append, last_step=last_step)
  end subroutine resolved_open_outputs

  !> The immersed boundary's own loads of the step just taken in bodies_loads.dat (if opened).
  subroutine resolved_record_fluid_step(self, solver)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(in) :: solver
    call loads_write(self%scene, solver%step, solver%time)
  end subroutine resolved_record_fluid_step

  subroutine resolved_finish(self, solver, steps)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(in) :: solver
    integer(i8), intent(in) :: steps
    call loads_close(self%scene)
  end subroutine resolved_finish

  !> The provider's state across fluid steps (group resolved_hydrodynamics of the transaction).
  subroutine resolved_write_checkpoint(self, transaction)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(checkpoint_t), intent(in) :: transaction
    associate (file => transaction%file)
      call h5_write_array(file, 'resolved_hydrodynamics/force', self%force)
      call h5_write_array(file, 'resolved_hydrodynamics/torque', self%torque)
      call h5_write_array(file, 'resolved_hydrodynamics/imposed_velocity', self%imposed_velocity)
      call h5_write_array(file, 'resolved_hydrodynamics/imposed_angular_velocity', self%imposed_angular_velocity)
      call h5_write_array(file, 'resolved_hydrodynamics/acceleration', self%acceleration)
      call h5_write_array(file, 'resolved_hydrodynamics/angular_acceleration', self%angular_acceleration)
      call h5_write_array(file, 'resolved_hydrodynamics/dt', self%dt)
      ! (3, n history_steps): the writer takes rank-2 arrays.
      call h5_write_array(file, 'resolved_hydrodynamics/earlier_acceleration', &
                          reshape(self%earlier_acceleration, [3, size(self%earlier_acceleration) / 3]))
      call h5_write_array(file, 'resolved_hydrodynamics/earlier_angular_acceleration', &
                          reshape(self%earlier_angular_acceleration, [3, size(self%earlier_angular_acceleration) / 3]))
      call h5_write_array(file, 'resolved_hydrodynamics/start_velocity', self%start_velocity)
      call h5_write_array(file, 'resolved_hydrodynamics/start_angular_velocity', self%start_angular_velocity)
      call h5_write_array(file, 'resolved_hydrodynamics/start_change', self%start_change)
      call h5_write_array(file, 'resolved_hydrodynamics/start_angular_change', self%start_angular_change)
      call h5_write_array(file, 'resolved_hydrodynamics/steps_since_start', self%steps_since_start)
    end associate
  end subroutine resolved_write_checkpoint

  subroutine resolved_read_checkpoint(self, restart)
    class(resolved_hydrodynamics_t), intent(inout) :: self
    type(checkpoint_t), intent(in) :: restart
    real(wp), allocatable :: flat(:, :)
    associate (file => restart%file)
      call h5_read_array(file, 'resolved_hydrodynamics/force', self%force)
      call h5_read_array(file, 'resolved_hydrodynamics/torque', self%torque)
      call h5_read_array(file, 'resolved_hydrodynamics/imposed_velocity', self%imposed_velocity)
      call h5_read_array(file, 'resolved_hydrodynamics/imposed_angular_velocity', self%imposed_angular_velocity)
      call h5_read_array(file, 'resolved_hydrodynamics/acceleration', self%acceleration)
      call h5_read_array(file, 'resolved_hydrodynamics/angular_acceleration', self%angular_acceleration)
      call h5_read_scalar(file, 'resolved_hydrodynamics/dt', self%dt)
      ! A checkpoint from before the history estimate has none: zero (explicit diffusion never uses it).
      if (h5_exists(file, 'resolved_hydrodynamics/earlier_acceleration')) then
        call h5_read_array(file, 'resolved_hydrodynamics/earlier_acceleration', flat)
        self%earlier_acceleration = reshape(flat, shape(self%earlier_acceleration))
        call h5_read_array(file, 'resolved_hydrodynamics/earlier_angular_acceleration', flat)
        self%earlier_angular_acceleration = reshape(flat, shape(self%earlier_angular_acceleration))
      end if
      ! Nor the start's jump (the history estimate with explicit diffusion): zero, no start term.
      if (h5_exists(file, 'resolved_hydrodynamics/start_velocity')) then
        call h5_read_array(file, 'resolved_hydrodynamics/start_velocity', self%start_velocity)
        call h5_read_array(file, 'resolved_hydrodynamics/start_angular_velocity', self%start_angular_velocity)
        call h5_read_array(file, 'resolved_hydrodynamics/start_change', self%start_change)
        call h5_read_array(file, 'resolved_hydrodynamics/start_angular_change', self%start_angular_change)
        call h5_read_scalar(file, 'resolved_hydrodynamics/steps_since_start', self%steps_since_start)
      end if
    end associate
    self%inject = .false.
  end subroutine resolved_read_checkpoint
end module resolved_hydrodynamics
