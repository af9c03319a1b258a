!> The resolved scene with immersed bodies in prescribed motion: the staged fluid step with the
!> immersed boundary (docs/design.md, the step's stages; ibm-notes section 8.1.5),
!>   bodies at t^{n+1} (reclassified when they move) -> fluid_predict (u*, with the uniform drive)
!>   -> impose on u* -> fluid_project -> re-impose on u^{n+1} -> fluid_finish_step -> loads,
!> and the per-step time series of every body's force and torque (bodies_loads.dat, docs/outputs.md):
!> both load methods every step, the momentum balance (immersed_boundary) and the face sum
!> (immersed_surface_loads); load_method picks the one written as the force and torque.
!> With &fluid viscous_scheme = 'crank_nicolson' the predictor's system holds the body rows
!> (immersed_predictor, solved with hypre), so u* needs no imposition.
!>
!> Prescribed motion of body n (lab frame): centre c(t) = c0 + U t + A sin(2 pi f t), velocity
!> U + 2 pi f A cos(2 pi f t), constant angular velocity Omega, orientation q(t) = rot(Omega t) q0.
module immersed_scene
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use vector_algebra, only: cross
  use error_handling, only: fatal
  use parallel_env, only: is_root
  use logger, only: log_line
  use text_series, only: drop_rows_after
  use text_format, only: real_text, int_text
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use fluid_grid, only: fluid_grid_t, allocate_field
  use fluid_solver, only: fluid_solver_t, fluid_predict, fluid_project, fluid_finish_step
  use hypre_solver, only: linear_solver_config_t
  use immersed_predictor, only: immersed_predictor_t, immersed_predictor_create, immersed_predictor_reclassified, &
                                immersed_predictor_first_guess
  use quaternion, only: quaternion_from_axis_angle, quaternion_product, quaternion_normalise
  use spheroid, only: spheroid_t, make_spheroid
  use icosphere_mesh, only: icosphere_mesh_t, build_icosphere_mesh
  use immersed_surface_loads, only: surface_loads_t, surface_loads_create, surface_loads_compute
  use config_bodies, only: bodies_config_t
  use immersed_geometry, only: immersed_body_t, node_fluid
  use immersed_boundary, only: immersed_boundary_t, ibm_settings_t, imposition_report_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use immersed_loads, only: ibm_begin_step, ibm_step_loads
  use immersed_diagnostics, only: cell_divergence_max, status_change_summary
  use immersed_pressure_extension, only: ibm_extend_pressure
  implicit none
  private
  public :: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step, &
            immersed_step_placed, motion_body, motion_velocity, loads_open, loads_write, loads_close, motions_from_config

  !> One body's shape and prescribed rigid motion.
  type :: prescribed_motion_t
    type(spheroid_t) :: shape
    real(wp) :: centre(3) = 0                  !< m, c0 at t = 0
    real(wp) :: orientation(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]   !< q0, body -> lab
    real(wp) :: velocity(3) = 0                !< m/s, U
    real(wp) :: angular_velocity(3) = 0        !< rad/s, Omega (lab frame, constant)
    real(wp) :: amplitude(3) = 0               !< m, A of the oscillation
    real(wp) :: frequency = 0                  !< Hz, f of the oscillation
    type(icosphere_mesh_t) :: mesh             !< &bodies geometry = 'mesh': the ghost nodes' surface (level -1: analytic)
  end type prescribed_motion_t

  !> How the scene is built (immersed_scene_create).
  type :: immersed_scene_options_t
    type(ibm_settings_t) :: settings           !< the imposition (coupling, ghost tolerance, sweeps, fluid density)
    real(wp) :: driving_force(3) = 0           !< N/m^3, uniform body force on the whole box (mean pressure gradient)
    !> Which loads are written as the force and torque: 'momentum' (the imposition's momentum
    !> balance) | 'surface' (the face sum, which then needs surface_level >= 0)
    character(len=16) :: load_method = 'momentum'
    !> The face sum's icosphere level (20 4^level faces; 2: 320 faces); -1: no face sum, its columns
    !> zero. It costs about 2 us per face per step (8 trilinear evaluations of the probes), so it is
    !> computed only when asked for; a level with 'momentum' computes both side by side.
    integer :: surface_level = -1
    !> The hypre solve of the Crank-Nicolson predictor with the body rows (unused with explicit diffusion)
    type(linear_solver_config_t) :: predictor_config = linear_solver_config_t(method='bicgstab', &
        preconditioner='user', tolerance=1.0e-8_wp, max_iterations=200)
  end type immersed_scene_options_t

  type :: immersed_scene_t
    type(immersed_boundary_t) :: ibm
    logical :: extend_pressure = .true.        !< ibm_extend_pressure after every step (moving bodies)
    type(prescribed_motion_t), allocatable :: motion(:)
    real(wp) :: driving_force(3) = 0           !< N/m^3, uniform body force on the whole box (mean pressure gradient)
    real(wp), allocatable :: force_u(:, :, :), force_v(:, :, :), force_w(:, :, :)   !< m/s^2, f / rho
    logical :: moving = .false.                !< some body changes its position or orientation
    real(wp), allocatable :: force(:, :), torque(:, :)   !< (3, n) N and N m of the last step (load_method's)
    character(len=16) :: load_method = 'momentum'        !< 'momentum' | 'surface': which loads are force, torque
    type(surface_loads_t) :: surface                     !< the face sum's quadrature
    real(wp), allocatable :: momentum_force(:, :), momentum_torque(:, :)   !< (3, n) by momentum balance
    real(wp), allocatable :: surface_force(:, :), surface_torque(:, :)     !< (3, n) by the face sum
    type(imposition_report_t) :: predicted, projected    !< the two impositions of the last step
    type(immersed_predictor_t) :: predictor    !< the Crank-Nicolson predictor with the body rows
    logical :: guess_from_velocity = .true.    !< its Krylov solve starts from u^n (else from b)
    real(wp) :: divergence = 0                 !< 1/s, largest |div u| after the re-imposition (cut cells)
    !> Timers: the whole immersed-boundary share of a step, and its parts (classification of the
    !> grid, the imposition sweeps, the loads), which nest inside it.
    integer :: timer = 0, timer_classify = 0, timer_impose = 0, timer_loads = 0
    integer :: loads_unit = 0
    logical :: loads_opened = .false.              !< this rank writes bodies_loads.dat
  end type immersed_scene_t

contains

  !> Place the bodies at t = solver%time and classify the nodes (collective), with the settings,
  !> the drive, the loads and the predictor's solve of options (immersed_scene_options_t).
  subroutine immersed_scene_create(scene, solver, motion, options)
    type(immersed_scene_t), intent(inout) :: scene
    type(fluid_solver_t), intent(inout) :: solver
    type(prescribed_motion_t), intent(in) :: motion(:)
    type(immersed_scene_options_t), intent(in) :: options
    integer :: n
    scene%motion = motion
    scene%ibm%settings = options%settings
    scene%driving_force = options%driving_force
    call allocate_field(solver%grid, scene%force_u)
    call allocate_field(solver%grid, scene%force_v)
    call allocate_field(solver%grid, scene%force_w)
    scene%force_u = options%driving_force(1) / solver%density
    scene%force_v = options%driving_force(2) / solver%density
    scene%force_w = options%driving_force(3) / solver%density
    scene%moving = .false.
    do n = 1, size(motion)
      scene%moving = scene%moving .or. any(motion(n)%velocity /= 0.0_wp) .or. &
                     (any(motion(n)%amplitude /= 0.0_wp) .and. motion(n)%frequency /= 0.0_wp) .or. &
                     (any(motion(n)%angular_velocity /= 0.0_wp) .and. motion(n)%shape%a /= motion(n)%shape%b)
    end do
    allocate(scene%force(3, size(motion)), scene%torque(3, size(motion)))
    scene%force = 0
    scene%torque = 0
    scene%load_method = options%load_method
    if (scene%load_method /= 'momentum' .and. scene%load_method /= 'surface') &
      call fatal('immersed scene: load_method '''//trim(scene%load_method)//'''; allowed: momentum, surface')
    scene%surface%mesh_level = options%surface_level
    if (scene%surface%mesh_level >= 0) then
      call surface_loads_create(scene%surface, motion(:)%shape)
    else if (scene%load_method == 'surface') then
      call fatal('immersed scene: load_method ''surface'' without a face-sum mesh (surface_level < 0)')
    end if
    scene%momentum_force = scene%force; scene%momentum_torque = scene%force
    scene%surface_force = scene%force; scene%surface_torque = scene%force
    call place_bodies(scene, solver, solver%time, classify=.true.)
    if (solver%crank_nicolson) then
      call immersed_predictor_create(scene%predictor, solver%grid, options%predictor_config)
    end if
    scene%timer = timer_register('immersed boundary')
    scene%timer_classify = timer_register('  IB classification')
    scene%timer_impose = timer_register('  IB imposition')
    scene%timer_loads = timer_register('  IB loads')
  end subroutine immersed_scene_create

  !> One fluid step of length dt with the bodies of the prescribed motion at t^{n+1} (reclassified
  !> when they move; collective). fluid_force_*: a body force on the fluid (m/s^2, the Eswaran-Pope
  !> f^n on the faces; absent: none, as in fluid_predict), added to the uniform drive on the fluid
  !> nodes of the new placement only: the imposition replaces the bodies' nodes, so the force there
  !> would only add rho f over the body's nodes to its load (the drive, a mean pressure gradient,
  !> does act on the body and stays everywhere).
  subroutine immersed_step(scene, solver, dt, fluid_force_u, fluid_force_v, fluid_force_w)
    type(immersed_scene_t), intent(inout), target :: scene
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    real(wp), intent(in), optional :: fluid_force_u(0:, 0:, 0:), fluid_force_v(0:, 0:, 0:), fluid_force_w(0:, 0:, 0:)
    call timer_tic(scene%timer)
    call timer_tic(scene%timer_classify)
    call place_bodies(scene, solver, solver%time + dt, classify=scene%moving)
    call timer_toc(scene%timer_classify)
    call staged_step(scene, solver, dt, scene%moving, fluid_force_u, fluid_force_v, fluid_force_w)
  end subroutine immersed_step

  !> immersed_step with the bodies at t^{n+1} as the caller places them (free particles, module
  !> resolved_hydrodynamics) instead of the prescribed motion, always reclassified: bodies(n) with
  !> velocity(:, n) (m/s) and angular_velocity(:, n) (rad/s, lab frame).
  subroutine immersed_step_placed(scene, solver, dt, bodies, velocity, angular_velocity, fluid_force_u, &
                                  fluid_force_v, fluid_force_w)
    type(immersed_scene_t), intent(inout), target :: scene
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    type(immersed_body_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: velocity(:, :), angular_velocity(:, :)
    real(wp), intent(in), optional :: fluid_force_u(0:, 0:, 0:), fluid_force_v(0:, 0:, 0:), fluid_force_w(0:, 0:, 0:)
    call timer_tic(scene%timer)
    call timer_tic(scene%timer_classify)
    call ibm_set_bodies(scene%ibm, solver%grid, bodies, velocity, angular_velocity, classify=.true.)
    call timer_toc(scene%timer_classify)
    call staged_step(scene, solver, dt, .true., fluid_force_u, fluid_force_v, fluid_force_w)
  end subroutine immersed_step_placed

  !> The step after the placement (the scene timer running): the forces on the new placement,
  !> predict -> impose (or the predictor with the body rows) -> project -> re-impose -> loads ->
  !> pressure of the sealed cells -> finish. reclassified: the nodes' status may have changed.
  subroutine staged_step(scene, solver, dt, reclassified, fluid_force_u, fluid_force_v, fluid_force_w)
    type(immersed_scene_t), intent(inout), target :: scene
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    logical, intent(in) :: reclassified
    real(wp), intent(in), optional :: fluid_force_u(0:, 0:, 0:), fluid_force_v(0:, 0:, 0:), fluid_force_w(0:, 0:, 0:)
    if (present(fluid_force_u)) then
      associate (drive => scene%driving_force / solver%density, nodes => scene%ibm%geometry%component)
        scene%force_u = drive(1) + merge(fluid_force_u, 0.0_wp, nodes(1)%status == node_fluid)
        scene%force_v = drive(2) + merge(fluid_force_v, 0.0_wp, nodes(2)%status == node_fluid)
        scene%force_w = drive(3) + merge(fluid_force_w, 0.0_wp, nodes(3)%status == node_fluid)
      end associate
    end if
    call ibm_begin_step(scene%ibm, solver%grid, solver%u, solver%v, solver%w)
    call timer_toc(scene%timer)
    if (solver%crank_nicolson) then
      ! The body rows are part of the predictor's system (the predictor's time counts as the fluid's).
      if (reclassified) call immersed_predictor_reclassified(scene%predictor)
      scene%predictor%ibm => scene%ibm
      if (scene%guess_from_velocity) call immersed_predictor_first_guess(scene%predictor, solver%grid, solver%u, &
                                                                         solver%v, solver%w)
      call fluid_predict(solver, dt, scene%predictor, force_u=scene%force_u, force_v=scene%force_v, &
                         force_w=scene%force_w)
      scene%predictor%ibm => null()
      scene%predicted = scene%predictor%report
    else
      call fluid_predict(solver, dt, force_u=scene%force_u, force_v=scene%force_v, force_w=scene%force_w)
      call timer_tic(scene%timer)
      call timer_tic(scene%timer_impose)
      call ibm_impose(scene%ibm, solver%grid, solver%explicit_old_u, solver%explicit_old_v, solver%explicit_old_w, &
                      scene%predicted)
      call timer_toc(scene%timer_impose)
      call timer_toc(scene%timer)
    end if
    call fluid_project(solver)
    call timer_tic(scene%timer)
    call timer_tic(scene%timer_impose)
    call ibm_impose(scene%ibm, solver%grid, solver%u, solver%v, solver%w, scene%projected)
    scene%divergence = cell_divergence_max(solver%grid, solver%u, solver%v, solver%w)
    call timer_toc(scene%timer_impose)
    call timer_tic(scene%timer_loads)
    call ibm_step_loads(scene%ibm, solver%grid, solver%u, solver%v, solver%w, dt, scene%momentum_force, &
                        scene%momentum_torque)
    ! The face sum with u^{n+1} and p^{n+1/2}, the pressure fluid_project left (immersed_surface_loads).
    if (scene%surface%mesh_level >= 0) &
      call surface_loads_compute(scene%surface, solver%grid, scene%ibm%bodies, scene%ibm%velocity, &
                                 scene%ibm%angular_velocity, solver%u, solver%v, solver%w, solver%pressure, &
                                 solver%viscosity, solver%density, scene%driving_force, scene%surface_force, &
                                 scene%surface_torque)
    if (scene%load_method == 'surface') then
      scene%force = scene%surface_force
      scene%torque = scene%surface_torque
    else
      scene%force = scene%momentum_force
      scene%torque = scene%momentum_torque
    end if
    call timer_toc(scene%timer_loads)
    if (scene%extend_pressure) call ibm_extend_pressure(scene%ibm, solver%grid, solver%pressure)
    call timer_toc(scene%timer)
    call fluid_finish_step(solver)
  end subroutine staged_step

  subroutine place_bodies(scene, solver, time, classify)
    type(immersed_scene_t), intent(inout) :: scene
    type(fluid_solver_t), intent(in) :: solver
    real(wp), intent(in) :: time
    logical, intent(in) :: classify
    type(immersed_body_t), allocatable :: bodies(:)
    real(wp), allocatable :: velocity(:, :), angular_velocity(:, :)
    integer :: n
    allocate(bodies(size(scene%motion)), velocity(3, size(scene%motion)), angular_velocity(3, size(scene%motion)))
    do n = 1, size(scene%motion)
      bodies(n) = motion_body(scene%motion(n), time, [solver%grid%lx, solver%grid%ly, solver%grid%lz])
      velocity(:, n) = motion_velocity(scene%motion(n), time)
      angular_velocity(:, n) = scene%motion(n)%angular_velocity
    end do
    call ibm_set_bodies(scene%ibm, solver%grid, bodies, velocity, angular_velocity, classify)
  end subroutine place_bodies

  !> The bodies of the deck's &bodies group (the density is the fluid's: prescribed motion needs
  !> none); the deck's checks have refused bodies too thin for the grid (config_checks).
  function motions_from_config(cfg) result(motion)
    type(bodies_config_t), intent(in) :: cfg
    type(prescribed_motion_t), allocatable :: motion(:)
    real(wp) :: axis(3), ex(3)
    integer :: n
    allocate(motion(cfg%count))
    ex = [1.0_wp, 0.0_wp, 0.0_wp]
    do n = 1, cfg%count
      if (trim(cfg%shape(n)) == 'sphere') then
        motion(n)%shape = make_spheroid('sphere', cfg%radius(n), 1.0_wp)
      else
        motion(n)%shape = make_spheroid(trim(cfg%shape(n)), cfg%radius(n), 1.0_wp, cfg%aspect_ratio(n))
      end if
      motion(n)%centre = cfg%centre(:, n)
      axis = cfg%axis(:, n)
      if (norm2(axis) > 0.0_wp) then
        axis = axis / norm2(axis)
        if (norm2(cross(ex, axis)) > 1.0e-12_wp) then
          motion(n)%orientation = quaternion_from_axis_angle(cross(ex, axis), acos(max(-1.0_wp, min(1.0_wp, axis(1)))))
        else if (axis(1) < 0.0_wp) then
          motion(n)%orientation = quaternion_from_axis_angle([0.0_wp, 0.0_wp, 1.0_wp], acos(-1.0_wp))
        end if
      end if
      motion(n)%velocity = cfg%velocity(:, n)
      motion(n)%angular_velocity = cfg%angular_velocity(:, n)
      motion(n)%amplitude = cfg%oscillation_amplitude(:, n)
      motion(n)%frequency = cfg%oscillation_frequency(n)
      if (cfg%geometry == 'mesh') call build_icosphere_mesh(motion(n)%shape, cfg%mesh_level, motion(n)%mesh)
    end do
  end function motions_from_config

  !> The body at time t, its centre wrapped into the box.
  pure function motion_body(motion, time, box) result(body)
    type(prescribed_motion_t), intent(in) :: motion
    real(wp), intent(in) :: time, box(3)
    type(immersed_body_t) :: body
    body%shape = motion%shape
    body%mesh = motion%mesh
    body%centre = modulo(motion%centre + motion%velocity * time + motion%amplitude * sin(two_pi * motion%frequency * time), &
                         box)
    body%orientation = quaternion_normalise(quaternion_product( &
        quaternion_from_axis_angle(motion%angular_velocity, norm2(motion%angular_velocity) * time), motion%orientation))
  end function motion_body

  pure function motion_velocity(motion, time) result(velocity)
    type(prescribed_motion_t), intent(in) :: motion
    real(wp), intent(in) :: time
    real(wp) :: velocity(3)
    velocity = motion%velocity + two_pi * motion%frequency * motion%amplitude * cos(two_pi * motion%frequency * time)
  end function motion_velocity

  !> Open the loads time series (root; a new file with its header, or appended on restart).
  subroutine loads_open(scene, path, append, last_step)
    type(immersed_scene_t), intent(inout) :: scene
    character(len=*), intent(in) :: path
    logical, intent(in) :: append
    integer(i8), intent(in) :: last_step   !< on a restart: the checkpoint's step (later rows are dropped)
    integer :: ios
    logical :: exists
    character(len=256) :: message
    if (.not. is_root()) return
    inquire(file=path, exist=exists)
    ! A row: step, then time, body, force(3), torque(3), sweeps, residual, slip, divergence, and the
    ! loads of both methods: momentum force(3), torque(3), surface force(3), torque(3).
    if (append .and. exists) call drop_rows_after(path, last_step, 24)
    if (append) then
      open(newunit=scene%loads_unit, file=path, status='unknown', position='append', action='write', iostat=ios, &
           iomsg=message)
    else
      open(newunit=scene%loads_unit, file=path, status='replace', action='write', iostat=ios, iomsg=message)
    end if
    if (ios /= 0) call fatal('immersed scene: cannot open '//path//': '//trim(message), collective=.false.)
    scene%loads_opened = .true.
    if (.not. append) write(scene%loads_unit, '(a)') '# step time_s body force_x_N force_y_N force_z_N ' // &
        'torque_x_Nm torque_y_Nm torque_z_Nm sweeps residual slip divergence_per_s ' // &
        'momentum_force_x_N momentum_force_y_N momentum_force_z_N momentum_torque_x_Nm momentum_torque_y_Nm ' // &
        'momentum_torque_z_Nm surface_force_x_N surface_force_y_N surface_force_z_N surface_torque_x_Nm ' // &
        'surface_torque_y_Nm surface_torque_z_Nm'
  end subroutine loads_open

  !> One row per body for the step just taken (root).
  subroutine loads_write(scene, step, time)
    type(immersed_scene_t), intent(in) :: scene
    integer(i8), intent(in) :: step
    real(wp), intent(in) :: time
    integer :: n
    if (.not. scene%loads_opened) return
    do n = 1, size(scene%motion)
      write(scene%loads_unit, '(i0,1x,es23.16,1x,i0,6(1x,es23.16),1x,i0,3(1x,es10.3),12(1x,es23.16))') step, time, &
          n, scene%force(:, n), scene%torque(:, n), scene%predicted%sweeps, scene%predicted%residual, &
          scene%projected%largest_change, scene%divergence, scene%momentum_force(:, n), scene%momentum_torque(:, n), &
          scene%surface_force(:, n), scene%surface_torque(:, n)
    end do
    flush(scene%loads_unit)
  end subroutine loads_write

  subroutine loads_close(scene)
    type(immersed_scene_t), intent(inout) :: scene
    integer :: n
    if (scene%loads_opened) close(scene%loads_unit)
    scene%loads_opened = .false.
    if (scene%predictor%builds > 0 .and. scene%predictor%method == 'capacitance') then
      ! Crank-Nicolson: the predicted report is the predictor's Krylov solve (immersed_predictor).
      call log_line('immersed scene: Crank-Nicolson predictor with the body rows: GMRES on the ghost rows with the '// &
          'FFT Helmholtz solve, body rows listed '//int_text(scene%predictor%builds)//' times in '// &
          real_text(scene%predictor%build_seconds)//' s, FFT solves '//int_text(scene%predictor%fft_solves)// &
          ' (local capacitance preconditioner: '//int_text(scene%predictor%preconditioner_iterations)// &
          ' GMRES iterations), solves '//real_text(scene%predictor%solve_seconds)// &
          ' s; last step GMRES iterations '//int_text(scene%predicted%sweeps)//', relative residual '// &
          real_text(scene%predicted%residual)//', slip '//real_text(scene%projected%largest_change)// &
          ', cut-cell divergence '//real_text(scene%divergence)//' 1/s')
    else if (scene%predictor%builds > 0) then
      call log_line('immersed scene: Crank-Nicolson predictor with the body rows: '// &
          trim(scene%predictor%config%method)//' + '//trim(merge('FFT Helmholtz   ', scene%predictor%config%preconditioner, &
          scene%predictor%config%preconditioner == 'user'))//', matrices built '//int_text(scene%predictor%builds)// &
          ' times in '//real_text(scene%predictor%build_seconds)//' s ('//int_text(scene%predictor%updates)// &
          ' of the component matrices only had new values), solves '//real_text(scene%predictor%solve_seconds)// &
          ' s; last step hypre iterations '//int_text(scene%predicted%sweeps)//', relative residual '// &
          real_text(scene%predicted%residual)//', slip '//real_text(scene%projected%largest_change)// &
          ', cut-cell divergence '//real_text(scene%divergence)//' 1/s')
    else
      call log_line('immersed scene: last step sweeps '//int_text(scene%predicted%sweeps)//' (plane exchanges '// &
                    int_text(scene%predicted%exchanges)//')'// &
                    ', residual '//real_text(scene%predicted%residual)//', slip '// &
                    real_text(scene%projected%largest_change)//', cut-cell divergence '//real_text(scene%divergence)//' 1/s')
    end if
    do n = 1, size(scene%motion)
      if (scene%surface%mesh_level < 0) exit   ! no face sum: nothing to compare
      call log_line('immersed scene: body '//int_text(n)//' last step |F| momentum '// &
                    real_text(norm2(scene%momentum_force(:, n)))//' N, surface '//real_text(norm2(scene%surface_force(:, n)))// &
                    ' N, |difference| '//real_text(norm2(scene%surface_force(:, n) - scene%momentum_force(:, n)))// &
                    ' N; |T| momentum '//real_text(norm2(scene%momentum_torque(:, n)))//' N m, surface '// &
                    real_text(norm2(scene%surface_torque(:, n)))//' N m ('//trim(scene%load_method)//' written)')
    end do
    if (scene%moving) call log_line(status_change_summary(scene%ibm%changes))
  end subroutine loads_close
end module immersed_scene
