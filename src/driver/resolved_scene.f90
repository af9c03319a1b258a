!> The resolved scene: DNS of the periodic box, without bodies or with bodies in prescribed motion
!> (&scene particles = 'prescribed', the immersed boundary: immersed_scene).
!> The loop follows docs/design.md's data flow: time step -> momentum predictor + projection
!> (fluid_advance; with bodies the staged step of immersed_step) -> statistics, health check,
!> output, checkpoint.
module resolved_scene
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal
  use text_format, only: real_text, int_text
  use logger, only: log_line
  use wall_clock, only: wall_time
  use run_directory, only: run_file
  use checkpoint_files, only: checkpoint_t, checkpoint_begin, checkpoint_commit, checkpoint_open_newest, &
                              checkpoint_close
  use physical_constants, only: two_pi
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use initial_fields, only: set_rest, set_taylor_green, set_random_field
  use fluid_diagnostics, only: fluid_statistics_t, compute_fluid_statistics, advective_rate
  use time_step_control, only: next_time_step, explicit_viscous_limit
  use time_step_guard, only: check_time_step
  use fluid_restart, only: write_fluid_checkpoint, read_fluid_checkpoint, write_fluid_snapshot, read_initial_field
  use fluid_monitor, only: statistics_open, statistics_write, statistics_close, progress_line, timing_report
  use forcing_driver, only: forcing_driver_t, forcing_driver_start, forced_fluid_advance, &
                            forcing_driver_power_input, forcing_driver_write_checkpoint, forcing_driver_finish, &
                            forcing_driver_evaluate, forcing_driver_advance
  use flow_statistics_output, only: flow_output_t, flow_output_start, flow_output_due, flow_output_record, &
                                    flow_output_finish
  use parallel_env, only: global_sum
  use immersed_boundary, only: ibm_settings_t
  use immersed_diagnostics, only: status_change_summary
  use immersed_geometry, only: fallback_count, saturated_count, immersed_body_t
  use immersed_predictor, only: default_predictor_config
  use particle_output, only: particle_output_t, particle_output_flush, particle_output_close
  use bodies_particle_output, only: bodies_output_open, bodies_output_row
  use immersed_scene, only: immersed_scene_t, immersed_scene_create, immersed_step, motions_from_config, &
                            loads_open, loads_write, loads_close, motion_body
  use body_surface_output, only: body_pose_t
  implicit none
  private
  public :: run_resolved_scene
  public :: start_fluid, next_output_time   ! shared with the pair in the resolved fluid (resolved_pair_scene)

contains

  subroutine run_resolved_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t) :: solver
    type(fluid_statistics_t) :: stats
    type(forcing_driver_t) :: forcing   ! Eswaran-Pope body force (inactive when off)
    type(flow_output_t) :: flow         ! flow statistics (u_rms, epsilon, Re_lambda, spectrum), if switched on
    type(checkpoint_t) :: restart       ! the checkpoint continued from (open only while restoring)
    type(immersed_scene_t) :: bodies    ! immersed bodies in prescribed motion (particles = 'prescribed')
    type(particle_output_t) :: bodies_h5   ! their particles.h5
    logical :: with_bodies
    real(wp) :: dt, rate, viscous_limit, next_field_time, start_wall, step_wall
    integer(i8) :: first_step
    integer :: timer_io
    logical :: finite
    ! Ghost rows whose image point fell inside another body (gap under about two cells) and were
    ! moved back to the mid-gap (immersed_geometry): this step's count over all ranks, the sum over
    ! the run's steps, the steps with any, the most in one step.
    integer :: fallbacks, fallback_steps, fallback_most
    integer(i8) :: fallback_rows, saturated_rows   ! saturated: the Couette rows among them (gap below half a cell)

    call start_fluid(cfg, solver, restart)
    timer_io = timer_register('I/O')
    call forcing_driver_start(forcing, cfg, solver, restart)
    if (cfg%run%restart) call checkpoint_close(restart)   ! every component has its state back
    call flow_output_start(flow, cfg, solver)
    with_bodies = (cfg%scene%particles == 'prescribed')
    if (with_bodies) call start_bodies()
    viscous_limit = huge(1.0_wp)
    if (.not. solver%crank_nicolson) viscous_limit = explicit_viscous_limit(solver%grid%dx, solver%grid%dy, &
                                                                            solver%grid%dz, solver%viscosity)
    call statistics_open(run_file('fluid_statistics.dat'), append=cfg%run%restart, last_step=solver%step)
    next_field_time = next_output_time(solver%time, cfg%output%field_interval, cfg%run%end_time)
    if (.not. cfg%run%restart) then
      call compute_fluid_statistics(solver, 0.0_wp, stats)
      call statistics_write(solver%step, solver%time, 0.0_wp, stats)
      call output_fields(solver)
    end if
    first_step = solver%step
    fallbacks = 0; fallback_steps = 0; fallback_most = 0; fallback_rows = 0; saturated_rows = 0
    start_wall = wall_time()
    step_wall = start_wall

    ! rate: the advective rate sum(|u_i|/dx_i) of the current field, for the next step's dt and
    ! the CFL check of the step just taken (one pass over the field per step).
    call advective_rate(solver, rate, finite)
    do while (solver%time < cfg%run%end_time .and. solver%step < cfg%run%max_steps)
      dt = next_time_step(cfg%run%dt_mode, cfg%run%dt, cfg%run%cfl_target, rate, viscous_limit, solver%time, &
                          cfg%run%end_time)
      call check_time_step(cfg%run, solver, rate)   ! a collapsed CFL step stops the run
      if (with_bodies) then
        call bodies_step(dt)
      else
        call forced_fluid_advance(forcing, solver, dt)   ! fluid_advance with the body force f^n, then f^n+1
      end if

      call advective_rate(solver, rate, finite)
      if (.not. finite) call stop_run(solver, 'the velocity field is no longer finite (NaN or infinity) at step ')
      if (dt * rate > cfg%run%cfl_limit) call stop_run(solver, 'CFL number '//real_text(dt * rate)// &
          ' exceeds &run cfl_limit = '//real_text(cfg%run%cfl_limit)//' at step ')
      if (mod(solver%step, int(cfg%output%stats_interval, i8)) == 0) then
        call compute_fluid_statistics(solver, dt, stats)
        call statistics_write(solver%step, solver%time, dt, stats)
      end if
      if (flow_output_due(flow, solver%step)) call flow_output_record(flow, solver, &
                                                                     forcing_driver_power_input(forcing, solver))
      if (mod(solver%step, int(cfg%run%progress_interval, i8)) == 0) then
        call progress_line(solver%step, solver%time, dt, (wall_time() - step_wall) / cfg%run%progress_interval, &
            min(real(cfg%run%max_steps - solver%step, wp), (cfg%run%end_time - solver%time) / dt))
        step_wall = wall_time()
        ! With Crank-Nicolson the predicted report is the hypre solve's (immersed_predictor).
        if (with_bodies) call log_line('immersed boundary: '// &
            trim(merge('hypre iterations', 'sweeps          ', solver%crank_nicolson))//' '//int_text(bodies%predicted%sweeps)// &
            ', residual '//real_text(bodies%predicted%residual)//', slip after projection '// &
            real_text(bodies%projected%largest_change)//', cut-cell divergence '//real_text(bodies%divergence)// &
            ' 1/s, image-point fallbacks '//int_text(fallbacks))
        if (with_bodies .and. bodies%moving) call log_line(status_change_summary(bodies%ibm%changes))
      end if
      if (solver%time >= next_field_time * (1.0_wp - 1.0e-12_wp) .and. solver%time < cfg%run%end_time) then
        call output_fields(solver)
        next_field_time = next_output_time(solver%time, cfg%output%field_interval, cfg%run%end_time)
      end if
      if (cfg%output%checkpoint_interval > 0) then
        if (mod(solver%step, int(cfg%output%checkpoint_interval, i8)) == 0) call checkpoint(solver)
      end if
    end do

    call output_fields(solver)
    if (cfg%output%checkpoint_interval == 0 .or. &
        mod(solver%step, int(max(cfg%output%checkpoint_interval, 1), i8)) /= 0) call checkpoint(solver)
    call statistics_close()
    call forcing_driver_finish(forcing, solver)
    call flow_output_finish(flow)
    if (with_bodies) then
      call loads_close(bodies)
      call particle_output_close(bodies_h5)
      call log_line('immersed boundary: image-point fallbacks (image segment inside another body, moved back to '// &
          'the mid-gap) in '//int_text(fallback_steps)//' of '//int_text(solver%step - first_step)//' steps, '// &
          int_text(fallback_rows)//' ghost rows in all ('//int_text(saturated_rows)//' saturated Couette rows), at most '// &
          int_text(fallback_most)//' in one step')
    end if
    call timing_report(solver%step - first_step, wall_time() - start_wall)
    call log_line('resolved scene: '//trim(cfg%run%name)//' reached t = '//real_text(solver%time)//' s; '// &
        'time series '//run_file('fluid_statistics.dat')//', fields '//run_file('fields.xdmf')// &
        ', checkpoints '//run_file('checkpoints'))

  contains

    subroutine start_bodies()
      type(ibm_settings_t) :: settings
      settings%coupling = cfg%scene%ibm_coupling
      settings%tolerance = cfg%bodies%ghost_tolerance
      settings%max_sweeps = cfg%bodies%max_sweeps
      settings%fluid_density = cfg%fluid%density
      call immersed_scene_create(bodies, solver, motions_from_config(cfg%bodies, solver%grid), settings, &
                                 cfg%bodies%driving_force, cfg%bodies%load_method, &
                                 merge(cfg%bodies%mesh_level, -1, cfg%bodies%load_method == 'surface' .or. &
                                       cfg%bodies%compare_loads), &
                                 predictor_config=default_predictor_config(cfg%fluid%predictor_tolerance, &
                                 cfg%fluid%predictor_max_iterations))
      call loads_open(bodies, run_file('bodies_loads.dat'), append=cfg%run%restart, last_step=solver%step)
      call bodies_output_open(bodies_h5, run_file('particles.h5'), cfg%bodies, cfg%run%name, int(cfg%run%seed, i8), &
                              cfg%run%restart, solver%step)
      call log_line('immersed boundary: '//trim(cfg%scene%ibm_coupling)//' coupling, '// &
          int_text(cfg%bodies%count)//' bodies, loads every step in '//run_file('bodies_loads.dat'))
    end subroutine start_bodies

    !> One step with the bodies (immersed_step), their loads and fallbacks. With the forcing on, its
    !> f^n goes into the predictor with the drive and the OU processes advance after the step, in
    !> forced_fluid_advance's order.
    subroutine bodies_step(dt)
      real(wp), intent(in) :: dt
      if (forcing%active) then
        call forcing_driver_evaluate(forcing)
        call immersed_step(bodies, solver, dt, forcing%fx, forcing%fy, forcing%fz)
        call forcing_driver_advance(forcing, dt)
      else
        call immersed_step(bodies, solver, dt)
      end if
      call loads_write(bodies, solver%step, solver%time)
      call bodies_output_row(bodies_h5, bodies, solver%time, [solver%grid%lx, solver%grid%ly, solver%grid%lz])
      call count_fallbacks()
    end subroutine bodies_step

    !> This step's image-point fallbacks over all ranks (collective), added to the run's tally; the
    !> first step with any is named in the log.
    subroutine count_fallbacks()
      fallbacks = nint(global_sum(real(fallback_count(bodies%ibm%geometry), wp)))
      if (fallbacks == 0) return
      if (fallback_steps == 0) call log_line('immersed boundary: step '//int_text(solver%step)//': '// &
          int_text(fallbacks)//' ghost rows with the image point moved back to the mid-gap (another body within '// &
          'about two cells; linear extrapolation, docs/theory.md)')
      fallback_steps = fallback_steps + 1
      fallback_rows = fallback_rows + fallbacks
      saturated_rows = saturated_rows + nint(global_sum(real(saturated_count(bodies%ibm%geometry), wp)), i8)
      fallback_most = max(fallback_most, fallbacks)
    end subroutine count_fallbacks

    !> The snapshot, with the bodies' surfaces at their poses of this time when there are bodies.
    subroutine output_fields(solver)
      type(fluid_solver_t), intent(inout) :: solver
      type(body_pose_t), allocatable :: poses(:)
      type(immersed_body_t) :: placed
      integer :: n
      call timer_tic(timer_io)
      if (with_bodies) then
        allocate(poses(size(bodies%motion)))
        do n = 1, size(poses)
          placed = motion_body(bodies%motion(n), solver%time, [solver%grid%lx, solver%grid%ly, solver%grid%lz])
          poses(n) = body_pose_t(placed%shape, placed%centre, placed%orientation)
        end do
        call write_fluid_snapshot(solver, poses)
      else
        call write_fluid_snapshot(solver)
      end if
      call timer_toc(timer_io)
    end subroutine output_fields

    !> One checkpoint transaction: each component writes its group, then one commit.
    subroutine checkpoint(solver)
      type(fluid_solver_t), intent(inout) :: solver
      type(checkpoint_t) :: transaction
      call timer_tic(timer_io)
      if (with_bodies) call particle_output_flush(bodies_h5)
      call checkpoint_begin(transaction, solver%step)
      call write_fluid_checkpoint(transaction, solver)
      call forcing_driver_write_checkpoint(forcing, transaction)
      call checkpoint_commit(transaction, cfg%output%checkpoints_kept)
      call timer_toc(timer_io)
    end subroutine checkpoint

    !> A failed run still leaves its last field for a look in ParaView.
    subroutine stop_run(solver, reason)
      type(fluid_solver_t), intent(inout) :: solver
      character(len=*), intent(in) :: reason
      character(len=24) :: step_text
      write(step_text, '(i0)') solver%step
      call output_fields(solver)
      call fatal('resolved scene: '//reason//trim(step_text)//' (t = '//real_text(solver%time)//' s); '// &
          'the last field is in '//run_file('fields.xdmf')//'; reduce &run dt or cfl_target')
    end subroutine stop_run
  end subroutine run_resolved_scene

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
end module resolved_scene
