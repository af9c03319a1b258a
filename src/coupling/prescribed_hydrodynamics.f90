!> &scene particles = 'prescribed': bodies whose motion the deck prescribes (&bodies), resolved by
!> the immersed boundary (module immersed_scene: the staged fluid step with the bodies placed at
!> t^{n+1}), as a provider of module particle_hydrodynamics. The bodies are kinematic: they are not
!> in the particle system (the scene loop takes no particle sub-steps) and feel no load; the
!> provider writes their loads every fluid step (bodies_loads.dat, and particles.h5 in the pair
!> scenes' layout, module bodies_particle_output) and counts the ghost rows whose image point fell
!> inside another body (immersed_geometry).
module prescribed_hydrodynamics
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  use text_format, only: real_text, int_text
  use parallel_env, only: global_sum
  use run_directory, only: run_file
  use fluid_solver, only: fluid_solver_t
  use forcing_driver, only: forcing_driver_t, forcing_driver_evaluate, forcing_driver_advance
  use particle_system, only: particle_system_t, particle_loads_t
  use checkpoint_files, only: checkpoint_t
  use particle_output, only: particle_output_t, particle_output_flush, particle_output_close
  use body_surface_output, only: body_pose_t
  use immersed_diagnostics, only: status_change_summary
  use immersed_geometry, only: fallback_count, saturated_count, immersed_body_t
  use immersed_predictor, only: default_predictor_config
  use immersed_scene, only: immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step, &
                            motions_from_config, &
                            loads_open, loads_write, loads_close, motion_body
  use bodies_particle_output, only: bodies_output_open, bodies_output_row
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  implicit none
  private
  public :: prescribed_hydrodynamics_t, prescribed_hydrodynamics_create

  type, extends(particle_hydrodynamics_t) :: prescribed_hydrodynamics_t
    type(immersed_scene_t) :: bodies           !< the bodies in prescribed motion and their immersed boundary
    type(particle_output_t) :: output          !< their particles.h5
    !> Ghost rows whose image point fell inside another body (gap under about two cells) and were
    !> moved back to the mid-gap (immersed_geometry): the last step's count over all ranks, the sum
    !> over the run's steps, the steps with any, the most in one step; saturated: the Couette rows
    !> among them (gap below half a cell).
    integer :: fallbacks = 0, fallback_steps = 0, fallback_most = 0
    integer(i8) :: fallback_rows = 0, saturated_rows = 0
  contains
    procedure :: loads => no_loads
    procedure :: fluid_step => prescribed_fluid_step
    procedure :: record_fluid_step => prescribed_record
    procedure :: write_checkpoint => prescribed_write_checkpoint
    procedure :: log_progress => prescribed_log_progress
    procedure :: body_poses => prescribed_poses
    procedure :: finish => prescribed_finish
  end type prescribed_hydrodynamics_t

contains

  !> The bodies of &bodies at the solver's time, their loads file and particles.h5 (new, or
  !> continued after the solver's step on a restart; collective).
  subroutine prescribed_hydrodynamics_create(provider, cfg, solver)
    type(prescribed_hydrodynamics_t), intent(out) :: provider
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(inout) :: solver
    type(immersed_scene_options_t) :: options
    options%settings%coupling = cfg%scene%ibm_coupling
    options%settings%tolerance = cfg%bodies%ghost_tolerance
    options%settings%max_sweeps = cfg%bodies%max_sweeps
    options%settings%fluid_density = cfg%fluid%density
    options%driving_force = cfg%bodies%driving_force
    options%load_method = cfg%bodies%load_method
    if (cfg%bodies%load_method == 'surface' .or. cfg%bodies%compare_loads) options%surface_level = cfg%bodies%mesh_level
    options%predictor_config = default_predictor_config(cfg%fluid%predictor_tolerance, cfg%fluid%predictor_max_iterations)
    call immersed_scene_create(provider%bodies, solver, motions_from_config(cfg%bodies), options)
    call loads_open(provider%bodies, run_file('bodies_loads.dat'), append=cfg%run%restart, last_step=solver%step)
    call bodies_output_open(provider%output, run_file('particles.h5'), cfg%bodies, cfg%run%name, &
                            int(cfg%run%seed, i8), cfg%run%restart, solver%step)
    call log_line('immersed boundary: '//trim(cfg%scene%ibm_coupling)//' coupling, '// &
        int_text(cfg%bodies%count)//' bodies, loads every step in '//run_file('bodies_loads.dat'))
  end subroutine prescribed_hydrodynamics_create

  !> Kinematic bodies feel nothing (they are not in the particle system).
  subroutine no_loads(self, system, theta, loads)
    class(prescribed_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
  end subroutine no_loads

  !> One step with the bodies (immersed_step). With the forcing on, its f^n goes into the predictor
  !> with the drive and the OU processes advance after the step, in forced_fluid_advance's order.
  subroutine prescribed_fluid_step(self, solver, forcing, system, dt)
    class(prescribed_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver
    type(forcing_driver_t), intent(inout) :: forcing
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dt
    if (forcing%active) then
      call forcing_driver_evaluate(forcing)
      call immersed_step(self%bodies, solver, dt, forcing%fx, forcing%fy, forcing%fz)
      call forcing_driver_advance(forcing, dt)
    else
      call immersed_step(self%bodies, solver, dt)
    end if
  end subroutine prescribed_fluid_step

  !> The step's loads (bodies_loads.dat, particles.h5) and image-point fallbacks over all ranks
  !> (collective), added to the run's tally; the first step with any is named in the log.
  subroutine prescribed_record(self, solver)
    class(prescribed_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(in) :: solver
    call loads_write(self%bodies, solver%step, solver%time)
    call bodies_output_row(self%output, self%bodies, solver%time, [solver%grid%lx, solver%grid%ly, solver%grid%lz])
    self%fallbacks = nint(global_sum(real(fallback_count(self%bodies%ibm%geometry), wp)))
    if (self%fallbacks == 0) return
    if (self%fallback_steps == 0) call log_line('immersed boundary: step '//int_text(solver%step)//': '// &
        int_text(self%fallbacks)//' ghost rows with the image point moved back to the mid-gap (another body within '// &
        'about two cells; linear extrapolation, docs/theory.md)')
    self%fallback_steps = self%fallback_steps + 1
    self%fallback_rows = self%fallback_rows + self%fallbacks
    self%saturated_rows = self%saturated_rows + nint(global_sum(real(saturated_count(self%bodies%ibm%geometry), wp)), i8)
    self%fallback_most = max(self%fallback_most, self%fallbacks)
  end subroutine prescribed_record

  !> particles.h5 flushed to disk with the checkpoint (its rows restart from the checkpoint's step).
  subroutine prescribed_write_checkpoint(self, transaction)
    class(prescribed_hydrodynamics_t), intent(inout) :: self
    type(checkpoint_t), intent(in) :: transaction
    call particle_output_flush(self%output)
  end subroutine prescribed_write_checkpoint

  !> With Crank-Nicolson the predicted report is the predictor's Krylov solve (immersed_predictor).
  subroutine prescribed_log_progress(self, solver)
    class(prescribed_hydrodynamics_t), intent(in) :: self
    type(fluid_solver_t), intent(in) :: solver
    call log_line('immersed boundary: '// &
        trim(merge('Krylov iterations', 'sweeps           ', solver%crank_nicolson))//' '// &
        int_text(self%bodies%predicted%sweeps)//', residual '//real_text(self%bodies%predicted%residual)// &
        ', slip after projection '//real_text(self%bodies%projected%largest_change)//', cut-cell divergence '// &
        real_text(self%bodies%divergence)//' 1/s, image-point fallbacks '//int_text(self%fallbacks))
    if (self%bodies%moving) call log_line(status_change_summary(self%bodies%ibm%changes))
  end subroutine prescribed_log_progress

  !> The bodies' surfaces at their prescribed poses of the fluid's time.
  subroutine prescribed_poses(self, solver, system, poses)
    class(prescribed_hydrodynamics_t), intent(in) :: self
    type(fluid_solver_t), intent(in) :: solver
    type(particle_system_t), intent(in) :: system
    type(body_pose_t), allocatable, intent(out) :: poses(:)
    type(immersed_body_t) :: placed
    integer :: n
    allocate(poses(size(self%bodies%motion)))
    do n = 1, size(poses)
      placed = motion_body(self%bodies%motion(n), solver%time, [solver%grid%lx, solver%grid%ly, solver%grid%lz])
      poses(n) = body_pose_t(placed%shape, placed%centre, placed%orientation)
    end do
  end subroutine prescribed_poses

  subroutine prescribed_finish(self, solver, steps)
    class(prescribed_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(in) :: solver
    integer(i8), intent(in) :: steps
    call loads_close(self%bodies)
    call particle_output_close(self%output)
    call log_line('immersed boundary: image-point fallbacks (image segment inside another body, moved back to '// &
        'the mid-gap) in '//int_text(self%fallback_steps)//' of '//int_text(steps)//' steps, '// &
        int_text(self%fallback_rows)//' ghost rows in all ('//int_text(self%saturated_rows)// &
        ' saturated Couette rows), at most '//int_text(self%fallback_most)//' in one step')
  end subroutine prescribed_finish
end module prescribed_hydrodynamics
