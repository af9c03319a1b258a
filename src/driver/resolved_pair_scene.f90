!> The particle pair in the resolved fluid: &scene fluid = 'resolved', particles = 'pair'. One
!> driver for every &scene particle_coupling; what changes with it is the hydrodynamic-load
!> provider (module pair_hydrodynamics: 'point', module point_hydrodynamics; 'resolved', the immersed
!> boundary, module resolved_hydrodynamics).
!>
!> One step (docs/design.md, "The pair in the resolved fluid"): the fluid advances by the step its
!> own limits allow (&run dt_mode: CFL / diffusion limit, or &run dt), the provider sampling or
!> imposing the bodies; then the particles take &scene particle_substeps steps of dt /
!> particle_substeps, each one particle_system_step (the same step routine as the pair scenes:
!> Newton-Euler under the provider's loads of the current state plus DLVO, then closest points,
!> collision test and impulse, DLVO of the new state), each followed by the pair scene's collision
!> events and output sample (module pair_scene). The pair's end test (&run end_time, twice the
!> first-collision time, &pair end_rule, &run max_steps counted in fluid steps) is taken after
!> each fluid step, so a run ends on a fluid-step boundary.
!>
!> Start: the fluid as in the resolved scene (&fluid init, or the newest checkpoint), the pair as
!> in the pair scenes (&pair; centre = 'random' draws in the fluid's box; with &pair
!> relative_to_fluid the start velocities lie on top of the fluid's motion at each centre).
!> &pair hydrodynamics_from = 'first_contact': the sub-steps feel no hydrodynamic load before the
!> pair's first collision (the fluid step still sees the bodies).
!> Outputs: the pair scenes' particles.h5 and summary.json (fluid 'resolved_point' or
!> 'resolved_resolved'), whose samples
!> carry the hydrodynamic force and torque (force_hydrodynamic, torque_hydrodynamic), and the
!> resolved scene's fluid_statistics.dat, fields and flow statistics; with particle_coupling =
!> 'resolved' also bodies_loads.dat, the immersed boundary's own force and torque on each body after
!> every fluid step (momentum balance or face sum, before the added-mass stabilisation; the columns
!> of the prescribed scenes, docs/outputs.md). Checkpoints (every &output
!> checkpoint_interval fluid steps and at the end): one transaction with the groups fluid, forcing,
!> particles, pair_scene and the provider's own (resolved_hydrodynamics), so &run restart continues
!> bit for bit.
module resolved_pair_scene
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal
  use text_format, only: real_text, int_text
  use logger, only: log_line
  use wall_clock, only: wall_time
  use progress_meter, only: scientific_text
  use run_directory, only: run_file
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use checkpoint_files, only: checkpoint_t, checkpoint_begin, checkpoint_commit, checkpoint_close
  use fluid_solver, only: fluid_solver_t
  use fluid_diagnostics, only: fluid_statistics_t, compute_fluid_statistics, advective_rate
  use time_step_control, only: next_time_step, explicit_viscous_limit
  use time_step_guard, only: check_time_step
  use fluid_restart, only: write_fluid_checkpoint, write_fluid_snapshot
  use body_surface_output, only: system_body_poses
  use fluid_monitor, only: statistics_open, statistics_write, statistics_close, progress_line, timing_report
  use forcing_driver, only: forcing_driver_t, forcing_driver_start, forcing_driver_power_input, &
                            forcing_driver_write_checkpoint, forcing_driver_finish
  use flow_statistics_output, only: flow_output_t, flow_output_start, flow_output_due, flow_output_record, &
                                    flow_output_finish
  use resolved_scene, only: start_fluid, next_output_time
  use rigid_body, only: set_angular_velocity_lab
  use pair_setup, only: pair_t, build_pair
  use particle_system, only: particle_system_t, particle_loads_t, particle_system_interact, particle_system_step, &
                             particle_system_set_added_inertia, particle_loads_zero
  use pair_outcome, only: pair_outcome_rules_t, pair_outcome_rules_of
  use particle_output, only: particle_output_t, run_summary_t, particle_output_close, write_summary_json
  use pair_scene, only: pair_loop_t, setup_system, record_interaction, run_finished, sampled, write_sample, &
                        finish_summary, log_pair, write_pair_scene_group, read_pair_scene_group, normal_approach_speed, &
                        open_particle_output
  use pair_hydrodynamics, only: pair_hydrodynamics_t
  use point_hydrodynamics, only: point_hydrodynamics_t, point_hydrodynamics_create
  use resolved_hydrodynamics, only: resolved_hydrodynamics_t, resolved_hydrodynamics_create
  use immersed_scene, only: loads_open, loads_write, loads_close
  use immersed_boundary, only: ibm_settings_t
  use immersed_predictor, only: default_predictor_config
  use point_particle_coupling, only: local_rotation, sample_velocity
  implicit none
  private
  public :: run_resolved_pair_scene

  !> The pair's only pair in the system's pair list.
  integer, parameter :: the_pair = 1

contains

  subroutine run_resolved_pair_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t) :: solver
    type(forcing_driver_t) :: forcing                    ! Eswaran-Pope body force (inactive when off)
    type(flow_output_t) :: flow                          ! flow statistics, if switched on
    type(fluid_statistics_t) :: stats
    type(checkpoint_t) :: restart                        ! open only while restoring
    class(pair_hydrodynamics_t), allocatable :: hydrodynamics
    type(pair_t) :: pair
    type(particle_system_t) :: system
    type(particle_loads_t) :: hydrodynamic               ! the provider's loads of the current state
    type(pair_outcome_rules_t) :: rules
    type(particle_output_t) :: output
    type(run_summary_t) :: summary
    type(pair_loop_t) :: loop
    real(wp) :: box(3), dt, dt_particle, step_start, rate, viscous_limit, next_field_time, wall_start, step_wall
    integer(i8) :: first_step
    integer :: substeps, substep, timer_particles, timer_io
    logical :: finite, finished

    call start_fluid(cfg, solver, restart)
    timer_io = timer_register('I/O')
    timer_particles = timer_register('particle sub-steps')
    call forcing_driver_start(forcing, cfg, solver, restart)
    box = [solver%grid%lx, solver%grid%ly, solver%grid%lz]
    call build_pair(cfg%pair, cfg%run%seed, pair, box)
    call setup_system(cfg, pair, system, box)
    rules = pair_outcome_rules_of(system%models)
    call log_pair(cfg, pair, rules)
    call create_hydrodynamics(cfg, solver, system, hydrodynamics)
    substeps = cfg%scene%particle_substeps
    loop%end_time = cfg%run%end_time
    summary%collisions = 0
    hydrodynamic = particle_loads_zero(system%n)
    if (cfg%run%restart) then
      call read_pair_scene_group(restart, cfg, system, loop, summary, hydrodynamic, output)
      call hydrodynamics%read_checkpoint(restart)
      call checkpoint_close(restart)   ! every component has its state back
      if (loop%step > 0 .and. abs(loop%time - solver%time) > 1.0e-12_wp * max(solver%time, tiny(1.0_wp))) &
        call fatal('resolved pair scene: the checkpoint''s particle time '//real_text(loop%time)// &
                   ' s is not its fluid time '//real_text(solver%time)//' s')
    else
      if (cfg%pair%relative_to_fluid) call add_fluid_motion(solver, system)
      call open_particle_output(cfg, pair, system, output)
      ! The collision test comes first, on the current state (as in the pair scenes).
      call particle_system_interact(system, cfg%run%dt / substeps)
    end if
    call hydrodynamics%prepare(solver, system)
    call flow_output_start(flow, cfg, solver)
    viscous_limit = huge(1.0_wp)
    if (.not. solver%crank_nicolson) viscous_limit = explicit_viscous_limit(solver%grid%dx, solver%grid%dy, &
                                                                            solver%grid%dz, solver%viscosity)
    call statistics_open(run_file('fluid_statistics.dat'), append=cfg%run%restart, last_step=solver%step)
    select type (hydrodynamics)
    type is (resolved_hydrodynamics_t)
      call loads_open(hydrodynamics%scene, run_file('bodies_loads.dat'), append=cfg%run%restart, last_step=solver%step)
    end select
    next_field_time = next_output_time(solver%time, cfg%output%field_interval, cfg%run%end_time)
    call log_line('resolved pair scene: particle coupling '''//trim(cfg%scene%particle_coupling)//''', '// &
        'particle step = fluid step / '//int_text(substeps)//'; particles.h5, summary.json')

    if (cfg%run%restart) then
      ! The checkpoint was written after its step's events, sample and end test: only the end test
      ! is repeated (the continued run's deck may set a later end).
      finished = run_finished(cfg, rules, system, summary, loop%time, solver%step, loop%end_time)
      if (finished .and. .not. sampled(cfg, loop%step)) call write_sample(output, loop%time, system, hydrodynamic)
    else
      call compute_fluid_statistics(solver, 0.0_wp, stats)
      call statistics_write(solver%step, solver%time, 0.0_wp, stats)
      call output_fields()
      call record_interaction(cfg, system, loop, output, summary)
      call felt_loads(0.0_wp)
      call write_sample(output, loop%time, system, hydrodynamic)
      finished = run_finished(cfg, rules, system, summary, loop%time, solver%step, loop%end_time)
    end if
    first_step = solver%step
    wall_start = wall_time()
    step_wall = wall_start
    call advective_rate(solver, rate, finite)

    do while (.not. finished)
      dt = next_time_step(cfg%run%dt_mode, cfg%run%dt, cfg%run%cfl_target, rate, viscous_limit, solver%time, &
                          cfg%run%end_time)
      call check_time_step(cfg%run, solver, rate)   ! a collapsed CFL step stops the run
      dt_particle = dt / substeps
      step_start = solver%time
      call hydrodynamics%fluid_step(solver, forcing, system, dt)
      ! The contact impulses of this step's sub-steps carry the added masses its loads move with.
      call particle_system_set_added_inertia(system, hydrodynamics%impulse_inertia(system))
      call advective_rate(solver, rate, finite)
      if (.not. finite) call stop_run('the velocity field is no longer finite (NaN or infinity) at step ')
      if (dt * rate > cfg%run%cfl_limit) call stop_run('CFL number '//real_text(dt * rate)// &
          ' exceeds &run cfl_limit = '//real_text(cfg%run%cfl_limit)//' at step ')
      if (mod(solver%step, int(cfg%output%stats_interval, i8)) == 0) then
        call compute_fluid_statistics(solver, dt, stats)
        call statistics_write(solver%step, solver%time, dt, stats)
      end if
      if (flow_output_due(flow, solver%step)) call flow_output_record(flow, solver, &
                                                                     forcing_driver_power_input(forcing, solver))
      select type (hydrodynamics)
      type is (resolved_hydrodynamics_t)
        call loads_write(hydrodynamics%scene, solver%step, solver%time)
      end select

      call timer_tic(timer_particles)
      call felt_loads(0.0_wp)
      do substep = 1, substeps
        call particle_system_step(system, dt_particle, hydrodynamic)
        loop%step = loop%step + 1
        ! The last sub-step lands on the fluid's time exactly (no drift between the two clocks).
        loop%time = step_start + substep * dt_particle
        if (substep == substeps) loop%time = solver%time
        call record_interaction(cfg, system, loop, output, summary)
        ! The loads of the new state: the next sub-step's, and the sample's.
        call felt_loads(real(substep, wp) / substeps)
        if (sampled(cfg, loop%step)) call write_sample(output, loop%time, system, hydrodynamic)
      end do
      call timer_toc(timer_particles)

      finished = run_finished(cfg, rules, system, summary, loop%time, solver%step, loop%end_time)
      if (finished .and. .not. sampled(cfg, loop%step)) call write_sample(output, loop%time, system, hydrodynamic)
      if (mod(solver%step, int(cfg%run%progress_interval, i8)) == 0 .or. finished) then
        call progress_line(solver%step, solver%time, dt, (wall_time() - step_wall) / cfg%run%progress_interval, &
            min(real(cfg%run%max_steps - solver%step, wp), (loop%end_time - solver%time) / dt))
        step_wall = wall_time()
        call log_line('  pair: gap = '//scientific_text(system%pairs(the_pair)%contact%gap)//' m  v_n = '// &
            scientific_text(normal_approach_speed(system, the_pair))//' m/s  collisions = '// &
            int_text(summary%collisions))
        if (len(hydrodynamics%progress_text()) > 0) call log_line(hydrodynamics%progress_text())
      end if
      if (finished) exit
      if (solver%time >= next_field_time * (1.0_wp - 1.0e-12_wp) .and. solver%time < cfg%run%end_time) then
        call output_fields()
        next_field_time = next_output_time(solver%time, cfg%output%field_interval, cfg%run%end_time)
      end if
      if (cfg%output%checkpoint_interval > 0) then
        if (mod(solver%step, int(cfg%output%checkpoint_interval, i8)) == 0) call checkpoint(last=.false.)
      end if
    end do

    call output_fields()
    ! The last state is always kept, so a finished run can be continued with a later &run end_time.
    if (solver%step > first_step) call checkpoint(last=.true.)
    call particle_output_close(output)
    call statistics_close()
    select type (hydrodynamics)
    type is (resolved_hydrodynamics_t)
      call loads_close(hydrodynamics%scene)
    end select
    call forcing_driver_finish(forcing, solver)
    call flow_output_finish(flow)
    call finish_summary(cfg, rules, system, loop, summary)
    summary%wall_time = wall_time() - wall_start
    call write_summary_json(run_file('summary.json'), summary)
    call timing_report(solver%step - first_step, wall_time() - wall_start)
    call log_line('resolved pair scene: outcome '//trim(summary%outcome)//' at t = '//real_text(solver%time)// &
        ' s; particles.h5, summary.json, fluid_statistics.dat and fields.xdmf in '//run_file(''))

  contains

    !> The provider's loads of the current state, or none before the first collision with &pair
    !> hydrodynamics_from = 'first_contact' (the fluid sees the moving bodies all the same).
    subroutine felt_loads(theta)
      real(wp), intent(in) :: theta
      if (cfg%pair%hydrodynamics_from == 'first_contact' .and. summary%collisions == 0) then
        hydrodynamic = particle_loads_zero(system%n)
      else
        call hydrodynamics%loads(system, theta, hydrodynamic)
      end if
    end subroutine felt_loads

    subroutine output_fields()
      call timer_tic(timer_io)
      call write_fluid_snapshot(solver, system_body_poses(system))
      call timer_toc(timer_io)
    end subroutine output_fields

    !> One checkpoint transaction: the fluid, the forcing, the particle system and the pair's loop.
    subroutine checkpoint(last)
      logical, intent(in) :: last
      type(checkpoint_t) :: transaction
      call timer_tic(timer_io)
      call checkpoint_begin(transaction, solver%step)
      call write_fluid_checkpoint(transaction, solver)
      call forcing_driver_write_checkpoint(forcing, transaction)
      call write_pair_scene_group(transaction, cfg, system, loop, summary, hydrodynamic, output, last)
      call hydrodynamics%write_checkpoint(transaction)
      call checkpoint_commit(transaction, cfg%output%checkpoints_kept)
      call timer_toc(timer_io)
    end subroutine checkpoint

    !> A failed run still leaves its last field for a look in ParaView.
    subroutine stop_run(reason)
      character(len=*), intent(in) :: reason
      character(len=24) :: step_text
      write(step_text, '(i0)') solver%step
      call output_fields()
      call fatal('resolved pair scene: '//reason//trim(step_text)//' (t = '//real_text(solver%time)//' s); '// &
          'the last field is in '//run_file('fields.xdmf')//'; reduce &run dt or cfl_target')
    end subroutine stop_run
  end subroutine run_resolved_pair_scene

  !> The provider of &scene particle_coupling (the deck checks refuse the ones not available).
  subroutine create_hydrodynamics(cfg, solver, system, hydrodynamics)
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(inout) :: solver
    type(particle_system_t), intent(in) :: system
    class(pair_hydrodynamics_t), allocatable, intent(out) :: hydrodynamics
    type(point_hydrodynamics_t), allocatable :: point
    type(resolved_hydrodynamics_t), allocatable :: resolved
    type(ibm_settings_t) :: settings
    select case (trim(cfg%scene%particle_coupling))
    case ('point')
      allocate(point)
      call point_hydrodynamics_create(point, solver, system, cfg%scene%added_mass)
      call move_alloc(point, hydrodynamics)
    case ('resolved')
      ! The imposition as for bodies in prescribed motion (&scene ibm_coupling, &bodies ghost_tolerance,
      ! max_sweeps, load_method, geometry, mesh_level; &fluid predictor_*); the bodies themselves are the pair's.
      settings%coupling = cfg%scene%ibm_coupling
      settings%tolerance = cfg%bodies%ghost_tolerance
      settings%max_sweeps = cfg%bodies%max_sweeps
      settings%fluid_density = cfg%fluid%density
      allocate(resolved)
      call resolved_hydrodynamics_create(resolved, solver, system, settings, cfg%bodies%load_method, &
                                         merge(cfg%bodies%mesh_level, -1, cfg%bodies%load_method == 'surface' .or. &
                                               cfg%bodies%compare_loads), &
                                         cfg%scene%added_mass, cfg%run%restart, cfg%pair%gravity, &
                                         default_predictor_config(cfg%fluid%predictor_tolerance, &
                                                                  cfg%fluid%predictor_max_iterations), &
                                         merge(cfg%bodies%mesh_level, -1, cfg%bodies%geometry == 'mesh'), &
                                         explicit_history=cfg%scene%added_mass_history)
      call move_alloc(resolved, hydrodynamics)
    case default
      ! The deck checks allow only 'point' and 'resolved'.
      call fatal('resolved pair scene: unknown &scene particle_coupling = '''//trim(cfg%scene%particle_coupling)// &
                 '''', collective=.false.)
    end select
  end subroutine create_hydrodynamics

  !> &pair relative_to_fluid: each body's start velocity on top of the fluid velocity at its centre,
  !> its angular velocity the fluid's local rotation (1/2) curl u there (the motion of the fluid it
  !> displaces, to first order). Collective.
  subroutine add_fluid_motion(solver, system)
    type(fluid_solver_t), intent(in) :: solver
    type(particle_system_t), intent(inout) :: system
    real(wp) :: centres(3, system%n), velocity(3, system%n), gradient(3, 3, system%n)
    integer :: i
    do i = 1, system%n
      centres(:, i) = system%bodies(i)%position
    end do
    call sample_velocity(solver%grid, solver%u, solver%v, solver%w, centres, velocity, gradient)
    do i = 1, system%n
      system%bodies(i)%velocity = system%bodies(i)%velocity + velocity(:, i)
      call set_angular_velocity_lab(system%bodies(i), local_rotation(gradient(:, :, i)))
    end do
    call log_line('resolved pair scene: start velocities on top of the fluid''s: |u_f| = '// &
        scientific_text(norm2(velocity(:, 1)))//', '//scientific_text(norm2(velocity(:, 2)))//' m/s at the centres')
  end subroutine add_fluid_motion
end module resolved_pair_scene
