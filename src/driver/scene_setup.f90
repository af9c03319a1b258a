!> The scene's set-up for the scene loop (module scene_loop): the fluid and its initial state, the
!> particles' hydrodynamics provider the deck selects (module particle_hydrodynamics), chosen here
!> once, and the start velocities relative to the fluid.
module scene_setup
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal, input_error
  use logger, only: log_line
  use progress_meter, only: scientific_text
  use physical_constants, only: two_pi
  use checkpoint_files, only: checkpoint_t, checkpoint_open_newest
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use initial_fields, only: set_rest, set_taylor_green, set_random_field
  use fluid_restart, only: read_fluid_checkpoint, read_initial_field
  use text_format, only: int_text
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, set_angular_velocity_lab
  use particle_system, only: particle_system_t, particle_system_create
  use immersed_scene, only: prescribed_motion_t, motions_from_config
  use pair_protocol, only: particle_models_of
  use point_particle_coupling, only: local_rotation, sample_velocity
  use immersed_predictor, only: default_predictor_config
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  use no_hydrodynamics, only: no_hydrodynamics_t
  use stokes_hydrodynamics, only: stokes_hydrodynamics_t, stokes_hydrodynamics_create
  use point_hydrodynamics, only: point_hydrodynamics_t, point_hydrodynamics_create
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create, &
                                    resolved_hydrodynamics_options_t
  use prescribed_hydrodynamics, only: prescribed_hydrodynamics_t, prescribed_hydrodynamics_create
  implicit none
  private
  public :: start_fluid, next_output_time, hydrodynamics_of, add_fluid_motion, provider_name, place_free_bodies, &
            require_bodies_apart

contains

  !> Solver and initial state: the newest checkpoint on restart, else &fluid init.
  subroutine start_fluid(cfg, solver, restart)
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(inout) :: solver
    type(checkpoint_t), intent(out) :: restart   ! on restart: the newest valid checkpoint, left open
    call fluid_solver_create(solver, cfg%grid, cfg%fluid)
    if (cfg%run%restart) then
      call checkpoint_open_newest(restart)
      call read_fluid_checkpoint(restart, solver)
      call log_line('resolved scene: continuing from '//restart%path)
      return
    end if
    select case (trim(cfg%fluid%init))
    case ('rest')
      call set_rest(solver)
    case ('taylor_green')
      call set_taylor_green(solver, cfg%fluid%init_amplitude)
    case ('random')
      call set_random_field(solver, int(cfg%run%seed, i8), cfg%fluid%init_amplitude, &
                            cfg%fluid%init_peak_wavenumber * two_pi / cfg%grid%length_x)
    case ('file')
      call read_initial_field(solver, trim(cfg%fluid%init_file))
    end select
  end subroutine start_fluid

  !> The first multiple of interval after time (interval 0: only the start and the end).
  pure real(wp) function next_output_time(time, interval, end_time) result(next)
    real(wp), intent(in) :: time, interval, end_time
    if (interval > 0) then
      next = (aint(time / interval * (1.0_wp + 1.0e-12_wp)) + 1.0_wp) * interval
    else
      next = 2 * end_time + 1.0_wp
    end if
  end function next_output_time

  !> The provider name the deck selects: 'none', 'stokes', 'point', 'resolved' or 'prescribed'.
  function provider_name(cfg) result(name)
    type(agglo_config_t), intent(in) :: cfg
    character(len=:), allocatable :: name
    if (cfg%scene%fluid /= 'resolved') then
      name = trim(cfg%scene%fluid)                ! 'none' | 'stokes'
    else if (cfg%scene%particles == 'prescribed') then
      name = 'prescribed'
    else if (cfg%scene%particles == 'none') then
      name = 'none'                               ! the fluid alone
    else
      name = trim(cfg%scene%particle_coupling)    ! 'point' | 'resolved'
    end if
  end function provider_name

  !> The particles' hydrodynamics provider of the deck (provider_name), for the system's bodies in
  !> the solver's fluid (collective: the immersed boundary classifies the grid). The deck checks
  !> refuse the combinations not available.
  subroutine hydrodynamics_of(cfg, solver, system, hydrodynamics)
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(inout) :: solver
    type(particle_system_t), intent(in) :: system
    class(particle_hydrodynamics_t), allocatable, intent(out) :: hydrodynamics
    type(stokes_hydrodynamics_t), allocatable :: stokes
    type(point_hydrodynamics_t), allocatable :: point
    type(resolved_hydrodynamics_t), allocatable :: resolved
    type(prescribed_hydrodynamics_t), allocatable :: prescribed
    type(resolved_hydrodynamics_options_t) :: options
    select case (provider_name(cfg))
    case ('none')
      allocate(no_hydrodynamics_t :: hydrodynamics)
    case ('stokes')
      allocate(stokes)
      call stokes_hydrodynamics_create(stokes, system, cfg%fluid%density * cfg%fluid%viscosity)
      call move_alloc(stokes, hydrodynamics)
    case ('point')
      allocate(point)
      call point_hydrodynamics_create(point, solver, system, cfg%scene%added_mass)
      call move_alloc(point, hydrodynamics)
    case ('resolved')
      ! The imposition as for bodies in prescribed motion (&scene ibm_coupling, &bodies ghost_tolerance,
      ! max_sweeps, load_method, geometry, mesh_level; &fluid predictor_*); the bodies are the system's.
      options%settings%coupling = cfg%scene%ibm_coupling
      options%settings%tolerance = cfg%bodies%ghost_tolerance
      options%settings%max_sweeps = cfg%bodies%max_sweeps
      options%settings%fluid_density = cfg%fluid%density
      options%load_method = cfg%bodies%load_method
      if (cfg%bodies%load_method == 'surface' .or. cfg%bodies%compare_loads) options%surface_level = cfg%bodies%mesh_level
      options%stabilise = cfg%scene%added_mass
      options%restart = cfg%run%restart
      options%gravity = cfg%pair%gravity
      options%predictor_config = default_predictor_config(cfg%fluid%predictor_tolerance, &
                                                          cfg%fluid%predictor_max_iterations)
      if (cfg%bodies%geometry == 'mesh') options%geometry_level = cfg%bodies%mesh_level
      options%explicit_history = cfg%scene%added_mass_history
      allocate(resolved)
      call resolved_hydrodynamics_create(resolved, solver, system, options)
      call move_alloc(resolved, hydrodynamics)
    case ('prescribed')
      allocate(prescribed)
      call prescribed_hydrodynamics_create(prescribed, cfg, solver)
      call move_alloc(prescribed, hydrodynamics)
    case default
      call fatal('scene: no particle hydrodynamics '''//provider_name(cfg)//'''', collective=.false.)
    end select
  end subroutine hydrodynamics_of

  !> &pair relative_to_fluid: each body's start velocity on top of the fluid velocity at its centre,
  !> its angular velocity the fluid's local rotation (1/2) curl u there (the motion of the fluid it
  !> displaces, to first order). Collective.
  subroutine add_fluid_motion(solver, system)
    type(fluid_solver_t), intent(in) :: solver
    type(particle_system_t), intent(inout) :: system
    real(wp) :: centres(3, system%n), velocity(3, system%n), gradient(3, 3, system%n)
    character(len=:), allocatable :: speeds
    integer :: i
    do i = 1, system%n
      centres(:, i) = system%bodies(i)%position
    end do
    call sample_velocity(solver%grid, solver%u, solver%v, solver%w, centres, velocity, gradient)
    speeds = ''
    do i = 1, system%n
      system%bodies(i)%velocity = system%bodies(i)%velocity + velocity(:, i)
      call set_angular_velocity_lab(system%bodies(i), local_rotation(gradient(:, :, i)))
      if (i <= 4) speeds = speeds//merge(', ', '  ', i > 1)//scientific_text(norm2(velocity(:, i)))
    end do
    if (system%n > 4) speeds = speeds//', ... (rms '// &
        scientific_text(sqrt(sum(velocity**2) / system%n))//' over '//int_text(system%n)//' bodies)'
    call log_line('resolved fluid: the bodies'' start velocities on top of the fluid''s: |u_f| = '//speeds(3:)// &
        ' m/s at the centres')
  end subroutine add_fluid_motion
  !> &scene particles = 'free': the bodies of &bodies (shape, radius, aspect_ratio, centre, axis,
  !> velocity, angular_velocity; any number) of &pair density in the resolved fluid's periodic box,
  !> with the deck's particle models, moving under their loads. Their placement and orientation are
  !> those of the prescribed bodies (immersed_scene motions_from_config: the same deck).
  subroutine place_free_bodies(cfg, solver, system)
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(in) :: solver
    type(particle_system_t), intent(out) :: system
    type(prescribed_motion_t), allocatable :: motion(:)
    type(spheroid_t), allocatable :: shapes(:)
    type(rigid_body_t), allocatable :: bodies(:)
    integer :: n
    motion = motions_from_config(cfg%bodies)
    allocate(shapes(size(motion)), bodies(size(motion)))
    do n = 1, size(motion)
      if (trim(cfg%bodies%shape(n)) == 'sphere') then
        shapes(n) = make_spheroid('sphere', cfg%bodies%radius(n), cfg%pair%density)
      else
        shapes(n) = make_spheroid(trim(cfg%bodies%shape(n)), cfg%bodies%radius(n), cfg%pair%density, &
                                  cfg%bodies%aspect_ratio(n))
      end if
      call rigid_body_of_spheroid(bodies(n), shapes(n), motion(n)%centre, motion(n)%orientation, motion(n)%velocity)
      call set_angular_velocity_lab(bodies(n), motion(n)%angular_velocity)
    end do
    call particle_system_create(system, shapes, bodies, particle_models_of(cfg), &
                                box_length=[solver%grid%lx, solver%grid%ly, solver%grid%lz])
    call log_line('free bodies: '//int_text(system%n)//' bodies of density '//scientific_text(cfg%pair%density)// &
                  ' kg/m^3 placed by &bodies, moving under their loads')
  end subroutine place_free_bodies
  !> Free bodies placed by &bodies must start apart: after the first interaction (closest points of
  !> every pair) a pair at a gap <= 0 stops the run naming both bodies (collective: every rank
  !> computes the same gaps).
  subroutine require_bodies_apart(system)
    type(particle_system_t), intent(in) :: system
    integer :: p
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p))
        if (.not. (pair%contact%gap > 0.0_wp)) call input_error('bodies', 'centre(:, '//int_text(pair%second)//')', &
            'a body overlapping body '//int_text(pair%first)//' (gap '//scientific_text(pair%contact%gap)//' m)', &
            'bodies apart at the start (gap > 0)')
      end associate
    end do
  end subroutine require_bodies_apart
end module scene_setup
