!> The one time loop of every scene (docs/design.md, "The scene loop"). What the deck switches on
!> decides which stages run, never which loop:
!>   set-up       the fluid (&scene fluid = 'resolved': the initial field or the newest checkpoint,
!>                the forcing, the statistics files), the particle system (&scene particles = 'pair':
!>                the pair protocol's placement, module pair_protocol; 'free': the bodies of &bodies;
!>                'suspension': the random placement of module suspension_scene) and the particles'
!>                hydrodynamics provider (module particle_hydrodynamics: 'none', 'stokes', 'point',
!>                'resolved', 'prescribed'), selected once here (module scene_setup);
!>   per fluid step (with a fluid):
!>     fluid step   forcing -> predict -> couple (impose the bodies, or nothing) -> project -> loads,
!>                  as the provider takes it (the fluid alone: the fused particle-free fluid_advance);
!>     stop checks  a velocity field that is no longer finite, or a CFL number above &run cfl_limit,
!>                  stops the run with its last field written;
!>     fluid outputs the time series of the fluid (fluid_statistics.dat, flow statistics) and the
!>                  provider's (bodies_loads.dat);
!>   particle sub-steps (with particles): &scene particle_substeps steps of dt / particle_substeps,
!>                each one particle_system_step under the provider's loads (Newton-Euler, closest
!>                points, collisions, DLVO: the interaction), then the pair's events and samples
!>                and, in a suspension with DLVO, its bonds (module agglomerate_tracking) and the
!>                rows of clusters.h5 at the times of particles.h5's (module cluster_output);
!>                with &scene substep_bodies = 'near' only the bodies of the pairs that may come near
!>                in the fluid step (module near_bodies), the others first in one update of the
!>                provider over the whole step (single_step; docs/theory.md, "Near-pair sub-steps");
!>   end rule     &run end_time, max_steps, and the pair's (twice the first collision, 'settled');
!>   progress, field outputs (&output field_interval), checkpoint (&output checkpoint_interval).
!> Without a fluid (&scene fluid = 'none' or 'stokes') the same loop runs with no fluid stages and
!> the deck's fixed step (one particle step per loop step). Each stage is timed under its own name
!> (core/timer_registry; the breakdown at the end of the log).
!>
!> Checkpoints: one transaction with the groups of what runs (fluid, forcing; particles and
!> pair_scene; a suspension's agglomerates; the provider's own, e.g. resolved_hydrodynamics),
!> written at a fluid-step boundary after its events, sample and end test, so &run restart
!> continues bit for bit. The last state is always kept, so a finished run can be continued with a
!> later &run end_time.
module scene_loop
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal
  use text_format, only: real_text, int_text
  use logger, only: log_line
  use wall_clock, only: wall_time
  use progress_meter, only: progress_report, scientific_text
  use run_directory, only: run_file
  use timer_registry, only: timer_tic, timer_toc
  use checkpoint_files, only: checkpoint_t, checkpoint_begin, checkpoint_commit, checkpoint_open_newest, checkpoint_close
  use fluid_solver, only: fluid_solver_t
  use fluid_diagnostics, only: fluid_statistics_t, compute_fluid_statistics, advective_rate
  use time_step_control, only: next_time_step, explicit_viscous_limit
  use time_step_guard, only: check_time_step
  use fluid_restart, only: write_fluid_checkpoint, begin_fluid_snapshot
  use field_output, only: field_snapshot_t, field_snapshot_end
  use body_surface_output, only: body_pose_t, field_snapshot_add_bodies
  use fluid_monitor, only: statistics_open, statistics_write, statistics_close, progress_line, timing_report
  use run_context, only: run_context_t, run_context_start
  use forcing_driver, only: forcing_driver_t, forcing_driver_start, forcing_driver_power_input, &
                            forcing_driver_write_checkpoint, forcing_driver_finish
  use flow_statistics_output, only: flow_output_t, flow_output_start, flow_output_due, flow_output_record, &
                                    flow_output_finish
  use pair_setup, only: pair_t, build_pair
  use particle_system, only: particle_system_t, particle_loads_t, particle_system_interact, particle_system_step, &
                             particle_system_set_added_inertia, particle_loads_zero, particle_system_set_members, &
                             particle_search_gap, particle_system_all_members
  use near_bodies, only: near_bodies_t, near_bodies_find
  use point_particle_coupling, only: sample_start, sample_end
  use pair_outcome, only: pair_outcome_rules_t, pair_outcome_rules_of
  use particle_output, only: particle_output_t, run_summary_t, particle_output_close, write_summary_json, &
                             pair_run_metadata_t, particle_output_open
  use pair_protocol, only: pair_loop_t, setup_system, record_interaction, run_finished, sampled, write_sample, &
                           finish_summary, log_pair, write_pair_scene_group, read_pair_scene_group, &
                           normal_approach_speed, open_particle_output, pair_progress_detail, fluid_name, &
                           bodies_progress_detail
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  use scene_setup, only: start_fluid, next_output_time, hydrodynamics_of, add_fluid_motion, place_free_bodies, &
                         require_bodies_apart
  use suspension_scene, only: place_suspension, start_suspension_agglomerates, write_suspension_agglomerates, &
                              read_suspension_agglomerates
  use bond_graph, only: component_labels
  use agglomerate_tracking, only: agglomerate_tracker_t, agglomerate_tracker_update, agglomerate_bonds
  use cluster_output, only: cluster_output_t, cluster_output_row, cluster_output_close
  implicit none
  private
  public :: run_scene

  !> The pair's only pair in the system's pair list.
  integer, parameter :: the_pair = 1
  !> The most bodies of a suspension whose surfaces the field snapshots hold (320 faces, about
  !> 33 kB each: 1000 bodies add 33 MB to every snapshot).
  integer, parameter :: surface_bodies_most = 1000

contains

  subroutine run_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    ! What runs: a resolved fluid, free particles (the pair protocol's system), and their provider.
    logical :: with_fluid, with_particles, with_pair, with_suspension
    logical :: with_clusters                             ! a suspension with DLVO: bonds, clusters.h5
    character(len=:), allocatable :: scene_name
    type(fluid_solver_t) :: solver
    type(forcing_driver_t) :: forcing                    ! Eswaran-Pope body force (inactive when off)
    type(flow_output_t) :: flow                          ! flow statistics, if switched on
    type(fluid_statistics_t) :: stats
    type(checkpoint_t) :: restart                        ! open only while restoring
    class(particle_hydrodynamics_t), allocatable :: hydrodynamics
    type(pair_t) :: pair
    type(particle_system_t) :: system
    type(particle_loads_t) :: hydrodynamic               ! the provider's loads of the current state
    type(pair_outcome_rules_t) :: rules
    type(particle_output_t) :: output
    type(run_summary_t) :: summary
    type(agglomerate_tracker_t) :: tracker               ! the suspension's bonds (with_clusters)
    type(cluster_output_t) :: clusters                   ! clusters.h5 (with_clusters)
    type(pair_loop_t) :: loop                            ! the particles' clock and the pair's records
    type(run_context_t) :: context                       ! the run's monitor, meters, stage timers, wall clocks
    real(wp) :: dt, step_start, rate, viscous_limit, next_field_time
    integer :: substeps
    logical :: finite, finished
    type(near_bodies_t) :: near                          ! &scene substep_bodies = 'near': who takes the sub-steps
    logical :: near_only

    with_fluid = cfg%scene%fluid == 'resolved'
    with_pair = cfg%scene%particles == 'pair'
    with_suspension = cfg%scene%particles == 'suspension'
    with_particles = with_pair .or. cfg%scene%particles == 'free' .or. with_suspension
    scene_name = trim(merge('resolved pair scene', 'resolved scene     ', with_pair))
    if (cfg%scene%particles == 'free') scene_name = 'free bodies scene'
    if (.not. with_fluid) scene_name = 'pair scene'
    if (with_suspension) scene_name = 'suspension scene'
    with_clusters = .false.
    substeps = 1
    if (with_fluid .and. with_particles) substeps = cfg%scene%particle_substeps
    near_only = cfg%scene%substep_bodies == 'near'

    call set_up()
    context%first_step = loop_step()
    context%wall_start = wall_time()
    context%step_wall = context%wall_start
    if (with_fluid) call advective_rate(solver, rate, finite)

    do while (.not. finished)
      dt = time_step()
      if (with_fluid) call check_time_step(cfg%run, solver, rate)   ! a collapsed CFL step stops the run
      step_start = loop_time()
      if (with_fluid) then
        call fluid_step()
        call stop_checks()
        call fluid_outputs()
      end if
      if (with_particles) then
        call particle_substeps()
      else
        finished = .not. (solver%time < cfg%run%end_time .and. solver%step < cfg%run%max_steps)
      end if
      call progress()
      ! The fluid alone keeps the cadence on its last step (its final snapshot and checkpoint
      ! follow the loop); with particles the last step's are those after the loop.
      if (finished .and. with_particles) exit
      call field_output()
      call checkpoint_due()
    end do
    call finish()

  contains

    !> The fluid, the particles, the provider; the restart or the start's outputs.
    subroutine set_up()
      real(wp) :: box(3)
      if (with_fluid) then
        call start_fluid(cfg, solver, restart)
        call run_context_start(context, with_fluid, with_particles)
        call forcing_driver_start(forcing, cfg, solver, restart)
      else
        call run_context_start(context, with_fluid, with_particles)
        if (cfg%run%restart) call checkpoint_open_newest(restart)
      end if
      if (with_suspension) then
        call place_suspension(cfg, system)
        with_clusters = system%models%dlvo
        if (with_clusters) call start_suspension_agglomerates(cfg, system, tracker, clusters)
      else if (with_particles .and. .not. with_pair) then
        call place_free_bodies(cfg, solver, system)
      else if (with_pair) then
        if (with_fluid) then
          box = [solver%grid%lx, solver%grid%ly, solver%grid%lz]
          call build_pair(cfg%pair, cfg%run%seed, pair, box)
          call setup_system(cfg, pair, system, box)
        else
          call build_pair(cfg%pair, cfg%run%seed, pair)
          call setup_system(cfg, pair, system)
        end if
        rules = pair_outcome_rules_of(system%models, cfg%pair%settle_time)
        call log_pair(cfg, pair, rules)
      end if
      call hydrodynamics_of(cfg, solver, system, hydrodynamics)
      loop%end_time = cfg%run%end_time
      summary%collisions = 0
      hydrodynamic = particle_loads_zero(system%n)
      if (cfg%run%restart) then
        if (with_particles) call read_pair_scene_group(restart, cfg, system, loop, summary, hydrodynamic, output)
        if (with_clusters) call read_suspension_agglomerates(restart, tracker, clusters)
        if (.not. with_pair) loop%end_time = cfg%run%end_time   ! free bodies: no end at the first collision
        call hydrodynamics%read_checkpoint(restart)
        call checkpoint_close(restart)   ! every component has its state back
        if (with_fluid .and. with_particles .and. loop%step > 0 .and. &
            abs(loop%time - solver%time) > 1.0e-12_wp * max(solver%time, tiny(1.0_wp))) &
          call fatal('resolved pair scene: the checkpoint''s particle time '//real_text(loop%time)// &
                     ' s is not its fluid time '//real_text(solver%time)//' s')
      else if (with_particles) then
        ! A suspension starts with the fluid's velocity at its centres (plus its random velocities).
        if (with_fluid .and. (cfg%pair%relative_to_fluid .or. with_suspension)) call add_fluid_motion(solver, system)
        if (with_pair) then
          call open_particle_output(cfg, pair, system, output)
        else
          call open_bodies_output()
        end if
        ! The collision test comes first, on the current state: with a detection distance of
        ! v_n dt the pair is caught before a step could carry it into overlap.
        call particle_system_interact(system, cfg%run%dt / substeps)
        if (.not. with_pair) call require_bodies_apart(system)
      end if
      if (with_fluid) call start_fluid_outputs()
      if (with_particles .and. with_fluid) call log_line(scene_name//': particle coupling '''// &
          trim(cfg%scene%particle_coupling)//''', particle step = fluid step / '//int_text(substeps)// &
          '; particles.h5'//trim(merge(', summary.json', '              ', with_pair)))

      if (with_fluid .and. .not. cfg%run%restart) then
        call compute_fluid_statistics(solver, 0.0_wp, stats)
        call statistics_write(context%monitor, solver%step, solver%time, 0.0_wp, stats)
        call output_fields()
      end if
      if (with_particles) then
        if (cfg%run%restart) then
          ! The checkpoint was written after its step's events, sample and end test: only the end
          ! test is repeated (the continued run's deck may set a later end).
          finished = end_rule()
          if (finished .and. .not. sampled(cfg, loop%step)) call write_rows()
        else
          call record_particle_step()
          call felt_loads(0.0_wp)
          call write_rows()
          finished = with_fluid .and. end_rule()
        end if
      else
        finished = .not. (solver%time < cfg%run%end_time .and. solver%step < cfg%run%max_steps)
      end if
    end subroutine set_up

    !> The provider's preparation, the fluid's time series, the first field time.
    subroutine start_fluid_outputs()
      call hydrodynamics%prepare(solver, system)
      call flow_output_start(flow, cfg, solver)
      viscous_limit = huge(1.0_wp)
      if (.not. solver%crank_nicolson) viscous_limit = explicit_viscous_limit(solver%grid%dx, solver%grid%dy, &
                                                                              solver%grid%dz, solver%viscosity)
      call statistics_open(context%monitor, run_file('fluid_statistics.dat'), append=cfg%run%restart, &
                           last_step=solver%step)
      call hydrodynamics%open_outputs(cfg%run%restart, solver%step)
      next_field_time = next_output_time(solver%time, cfg%output%field_interval, cfg%run%end_time)
    end subroutine start_fluid_outputs

    !> The step the fluid's limits allow (&run dt_mode: CFL / diffusion limit, or &run dt); without
    !> a fluid the deck's step.
    real(wp) function time_step()
      if (with_fluid) then
        time_step = next_time_step(cfg%run%dt_mode, cfg%run%dt, cfg%run%cfl_target, rate, viscous_limit, &
                                   solver%time, cfg%run%end_time)
      else
        time_step = cfg%run%dt
      end if
    end function time_step

    !> Forcing -> predict -> couple -> project -> loads: the provider's fluid step.
    subroutine fluid_step()
      call timer_tic(context%timers%fluid_step)
      call hydrodynamics%fluid_step(solver, forcing, system, dt)
      ! The contact impulses of this step's sub-steps carry the added masses its loads move with.
      if (with_particles) call particle_system_set_added_inertia(system, hydrodynamics%impulse_inertia(system))
      call hydrodynamics%record_fluid_step(solver)
      call timer_toc(context%timers%fluid_step)
    end subroutine fluid_step

    !> rate: the advective rate sum(|u_i|/dx_i) of the new field, for the next step's dt and the
    !> CFL check of the step just taken (one pass over the field per step).
    subroutine stop_checks()
      call timer_tic(context%timers%stop_checks)
      call advective_rate(solver, rate, finite)
      if (.not. finite) call stop_run('the velocity field is no longer finite (NaN or infinity) at step ')
      if (dt * rate > cfg%run%cfl_limit) call stop_run('CFL number '//real_text(dt * rate)// &
          ' exceeds &run cfl_limit = '//real_text(cfg%run%cfl_limit)//' at step ')
      call timer_toc(context%timers%stop_checks)
    end subroutine stop_checks

    subroutine fluid_outputs()
      call timer_tic(context%timers%fluid_outputs)
      if (mod(solver%step, int(cfg%output%stats_interval, i8)) == 0) then
        call compute_fluid_statistics(solver, dt, stats)
        call statistics_write(context%monitor, solver%step, solver%time, dt, stats)
      end if
      if (flow_output_due(flow, solver%step)) call flow_output_record(flow, solver, &
                                                                     forcing_driver_power_input(forcing, solver))
      call timer_toc(context%timers%fluid_outputs)
    end subroutine fluid_outputs

    !> The particle sub-steps of this loop step (interact and step: particle_system_step), each
    !> followed by the pair's events, loads of the new state and sample; then the end rule.
    subroutine particle_substeps()
      real(wp) :: dt_particle
      integer :: substep
      call timer_tic(context%timers%particles)
      dt_particle = dt / substeps
      if (near_only) then
        ! The bodies of the pairs that may come near take the sub-steps; the others the whole
        ! step in one update (module near_bodies; docs/theory.md, "Near-pair sub-steps").
        call timer_tic('near-body search')
        call particle_system_all_members(system)   ! the search gap from every body's speed
        call near_bodies_find(near, system, hydrodynamics%centre_fluid_velocity(sample_start), &
                              hydrodynamics%centre_fluid_velocity(sample_end), dt, particle_search_gap(system, dt_particle))
        call particle_system_set_members(system, near%members(1:near%count))
        call timer_toc('near-body search')
        call timer_tic('one-step update')
        call hydrodynamics%single_step(system, near%single(1:system%n - near%count), dt)
        call timer_toc('one-step update')
      end if
      call felt_loads(0.0_wp)
      do substep = 1, substeps
        call particle_system_step(system, dt_particle, hydrodynamic)
        loop%step = loop%step + 1
        ! The last sub-step lands on the fluid's time exactly (no drift between the two clocks).
        loop%time = step_start + substep * dt_particle
        if (with_fluid .and. substep == substeps) loop%time = solver%time
        call record_particle_step()
        ! The loads of the new state: the next sub-step's, and the sample's.
        if (near_only .and. substep == substeps) then
          call hydrodynamics%loads(system, 1.0_wp, hydrodynamic)   ! every body's, for the samples
        else
          call felt_loads(real(substep, wp) / substeps)
        end if
        if (sampled(cfg, loop%step)) call write_rows()
      end do
      call timer_toc(context%timers%particles)
      finished = end_rule()
      if (finished .and. .not. sampled(cfg, loop%step)) call write_rows()
    end subroutine particle_substeps

    !> The events of the particle step just taken: the contact episodes (record_interaction) and, in
    !> a suspension with DLVO, the bond rule on every near pair (agglomerate_tracker_update).
    subroutine record_particle_step()
      if (with_clusters) then
        call record_interaction(cfg, system, loop, output, summary, tracker)
        call agglomerate_tracker_update(tracker, system, loop%time)
      else
        call record_interaction(cfg, system, loop, output, summary)
      end if
    end subroutine record_particle_step

    !> A row of particles.h5 and, with agglomerates, of clusters.h5 (the same times).
    subroutine write_rows()
      call write_sample(output, loop%time, system, hydrodynamic, bodies_layout=with_suspension)
      if (with_clusters) call cluster_output_row(clusters, loop%time, system, tracker)
    end subroutine write_rows

    !> The pair's end rule (module pair_protocol) at the loop's step; free bodies end at &run
    !> end_time or max_steps.
    logical function end_rule()
      if (with_pair) then
        end_rule = run_finished(cfg, rules, system, loop, loop_step())
      else
        end_rule = loop_step() >= cfg%run%max_steps .or. loop%time >= cfg%run%end_time * (1.0_wp - 1.0e-12_wp)
      end if
    end function end_rule

    !> particles.h5 of free bodies, in the pair scenes' layout (N bodies, their N (N - 1) / 2 pairs);
    !> a suspension's without the pairs (its near pairs change from step to step).
    subroutine open_bodies_output()
      type(pair_run_metadata_t) :: metadata
      metadata%name = cfg%run%name
      if (with_suspension) then
        metadata%shape = cfg%suspension%shape(1)
        if (any(system%shapes%aspect_ratio /= system%shapes(1)%aspect_ratio) .or. &
            any(system%shapes%radius /= system%shapes(1)%radius)) metadata%shape = 'mixed'
      else
        metadata%shape = cfg%bodies%shape(1)
        if (any(cfg%bodies%shape(2:system%n) /= cfg%bodies%shape(1))) metadata%shape = 'mixed'
      end if
      metadata%aspect_ratio = system%shapes(1)%aspect_ratio
      metadata%radius = system%shapes(1)%radius
      metadata%fluid = fluid_name(cfg)
      metadata%seed = int(cfg%run%seed, i8)
      metadata%bodies = system%n
      call particle_output_open(output, run_file('particles.h5'), metadata)
    end subroutine open_bodies_output

    function progress_detail() result(text)
      character(len=:), allocatable :: text
      if (with_pair) then
        text = pair_progress_detail(system)
      else
        text = bodies_progress_detail(system, summary%collisions)
      end if
    end function progress_detail

    !> The provider's loads of the current state, or none before the first collision with &pair
    !> hydrodynamics_from = 'first_contact' (the fluid sees the moving bodies all the same). The
    !> sub-grid lubrication is the unresolved part of the same fluid's force, so it waits for the
    !> first collision too (docs/theory.md, "Sub-grid lubrication").
    subroutine felt_loads(theta)
      real(wp), intent(in) :: theta
      logical :: felt
      felt = .not. (cfg%pair%hydrodynamics_from == 'first_contact' .and. summary%collisions == 0)
      system%models%lubrication = cfg%collision%lubrication .and. felt
      if (.not. felt) then
        hydrodynamic = particle_loads_zero(system%n)
      else if (near_only .and. allocated(system%members)) then
        call hydrodynamics%member_loads(system, theta, near%members(1:near%count), hydrodynamic)
      else
        call hydrodynamics%loads(system, theta, hydrodynamic)
      end if
    end subroutine felt_loads

    !> Loop steps: fluid steps with a fluid, particle steps without.
    integer(i8) function loop_step()
      if (with_fluid) then
        loop_step = solver%step
      else
        loop_step = loop%step
      end if
    end function loop_step

    real(wp) function loop_time()
      if (with_fluid) then
        loop_time = solver%time
      else
        loop_time = loop%time
      end if
    end function loop_time

    !> Every &run progress_interval loop steps (and at a pair's end): the progress line, with the
    !> pair's gap and approach speed and the provider's figures.
    subroutine progress()
      if (.not. with_fluid) then
        if (loop%step > context%first_step .and. &
            (mod(loop%step, int(cfg%run%progress_interval, i8)) == 0 .or. finished)) &
          call log_line(progress_report(context%meter, wall_time(), loop%step, loop%time, dt, &
                                        (wall_time() - context%wall_start) / real(loop%step - context%first_step, wp), &
                                        loop%end_time - loop%time, steps_left=real(cfg%run%max_steps - loop%step, wp), &
                                        detail=progress_detail()))
        return
      end if
      if (mod(solver%step, int(cfg%run%progress_interval, i8)) == 0 .or. (finished .and. with_particles)) then
        call progress_line(context%monitor, solver%step, solver%time, dt, &
            (wall_time() - context%step_wall) / cfg%run%progress_interval, &
            min(real(cfg%run%max_steps - solver%step, wp), (loop%end_time - solver%time) / dt))
        context%step_wall = wall_time()
        if (with_pair) call log_line('  pair: gap = '//scientific_text(system%pairs(the_pair)%contact%gap)// &
            ' m  v_n = '//scientific_text(normal_approach_speed(system, the_pair))//' m/s  contact episodes = '// &
            int_text(summary%contact_episodes)//' (impulses '//int_text(summary%collisions)//')')
        if (with_particles .and. .not. with_pair) call log_line(bodies_progress_detail(system, summary%collisions))
        if (near_only) call log_line('  sub-steps: '//int_text(near%count)//' bodies of '//int_text(near%near_pairs)// &
            ' pairs that may come near; '//int_text(system%n - near%count)//' in one update; misses so far '// &
            int_text(int(near%misses)))
        call hydrodynamics%log_progress(solver)
      end if
    end subroutine progress

    !> The snapshot at every &output field_interval of simulated time (the end's after the loop).
    subroutine field_output()
      if (.not. with_fluid) return
      if (solver%time >= next_field_time * (1.0_wp - 1.0e-12_wp) .and. solver%time < cfg%run%end_time) then
        call output_fields()
        next_field_time = next_output_time(solver%time, cfg%output%field_interval, cfg%run%end_time)
      end if
    end subroutine field_output

    !> Every &output checkpoint_interval loop steps (none at a pair's last step: the end writes it).
    subroutine checkpoint_due()
      if (cfg%output%checkpoint_interval <= 0) return
      if (loop_step() <= context%first_step) return
      if (mod(loop_step(), int(cfg%output%checkpoint_interval, i8)) == 0) call checkpoint(last=.false.)
    end subroutine checkpoint_due

    !> The fluid's snapshot, with the bodies' surfaces when there are bodies (a suspension of more
    !> than surface_bodies_most bodies: the fluid alone; its bodies are in particles.h5).
    subroutine output_fields()
      type(body_pose_t), allocatable :: poses(:)
      type(field_snapshot_t) :: snapshot
      call timer_tic(context%timers%fields)
      if (.not. (with_suspension .and. system%n > surface_bodies_most)) &
        call hydrodynamics%body_poses(solver, system, poses)
      if (allocated(poses) .and. with_clusters) call label_clusters(poses)
      call begin_fluid_snapshot(snapshot, solver)
      if (allocated(poses)) &
        call field_snapshot_add_bodies(snapshot, poses, [solver%grid%lx, solver%grid%ly, solver%grid%lz])
      call field_snapshot_end(snapshot)
      call timer_toc(context%timers%fields)
    end subroutine output_fields

    !> Each body's cluster (1..K, numbered by smallest body) on its drawn surface.
    subroutine label_clusters(poses)
      type(body_pose_t), intent(inout) :: poses(:)
      integer, allocatable :: labels(:)
      integer :: count
      if (size(poses) /= system%n) return
      allocate(labels(system%n))
      call component_labels(system%n, agglomerate_bonds(tracker), labels, count)
      poses%cluster = labels
    end subroutine label_clusters

    !> One checkpoint transaction: each component that runs writes its group, then one commit.
    subroutine checkpoint(last)
      logical, intent(in) :: last          !< the finished run's last state
      type(checkpoint_t) :: transaction
      call timer_tic(context%timers%checkpoint)
      call checkpoint_begin(transaction, loop_step())
      if (with_fluid) then
        call write_fluid_checkpoint(transaction, solver)
        call forcing_driver_write_checkpoint(forcing, transaction)
      end if
      if (with_particles) call write_pair_scene_group(transaction, cfg, system, loop, summary, hydrodynamic, output, last)
      if (with_clusters) call write_suspension_agglomerates(transaction, tracker, clusters, &
                                                            without_last_row=last .and. .not. sampled(cfg, loop%step))
      call hydrodynamics%write_checkpoint(transaction)
      call checkpoint_commit(transaction, cfg%output%checkpoints_kept)
      call timer_toc(context%timers%checkpoint)
    end subroutine checkpoint

    !> The last snapshot and checkpoint, the outputs closed, the summary and the timing breakdown.
    subroutine finish()
      integer(i8) :: steps
      steps = loop_step() - context%first_step
      if (with_fluid) call output_fields()
      if (with_particles) then
        ! The last state is always kept (checkpoint_interval = 0: only there), so a finished run
        ! can be continued with a later &run end_time.
        if (steps > 0) call checkpoint(last=.true.)
        call particle_output_close(output)
        if (with_clusters) call cluster_output_close(clusters, tracker)
      else if (cfg%output%checkpoint_interval == 0 .or. &
               mod(solver%step, int(max(cfg%output%checkpoint_interval, 1), i8)) /= 0) then
        call checkpoint(last=.true.)   ! the fluid alone: unless its last step was a checkpoint's
      end if
      if (with_fluid) then
        call statistics_close(context%monitor)
        call hydrodynamics%finish(solver, steps)
        call forcing_driver_finish(forcing, solver)
        call flow_output_finish(flow)
      end if
      if (with_pair) then
        call finish_summary(cfg, rules, system, loop, summary)
        summary%wall_time = wall_time() - context%wall_start
        call write_summary_json(run_file('summary.json'), summary)
      end if
      call timing_report(steps, wall_time() - context%wall_start)
      if (.not. with_fluid .and. .not. with_pair) then
        call log_line(scene_name//': '//int_text(system%n)//' bodies, '//int_text(summary%collisions)// &
            ' collisions, t = '//real_text(loop%time)//' s; particles.h5 in '//run_file(''))
      else if (.not. with_fluid) then
        call log_line('pair scene: outcome '//trim(summary%outcome)//'; particles.h5 and summary.json written')
        if (loop%step >= cfg%run%max_steps .and. loop%time < loop%end_time * (1.0_wp - 1.0e-12_wp)) &
          call log_line('pair scene: stopped by &run max_steps = '//int_text(cfg%run%max_steps)//' at t = '// &
                        real_text(loop%time)//' s, before the end time '//real_text(loop%end_time)//' s')
      else if (with_particles .and. .not. with_pair) then
        call log_line(scene_name//': '//int_text(system%n)//' bodies, '//int_text(summary%collisions)// &
            ' collisions, t = '//real_text(solver%time)//' s; particles.h5, fluid_statistics.dat, fields.xdmf'// &
            trim(merge(' and bodies_loads.dat', '                     ', cfg%scene%particle_coupling == 'resolved'))// &
            ' in '//run_file(''))
      else if (with_particles) then
        call log_line('resolved pair scene: outcome '//trim(summary%outcome)//' at t = '//real_text(solver%time)// &
            ' s; particles.h5, summary.json, fluid_statistics.dat and fields.xdmf in '//run_file(''))
      else
        call log_line('resolved scene: '//trim(cfg%run%name)//' reached t = '//real_text(solver%time)//' s; '// &
            'time series '//run_file('fluid_statistics.dat')//', fields '//run_file('fields.xdmf')// &
            ', checkpoints '//run_file('checkpoints'))
      end if
    end subroutine finish

    !> A failed run still leaves its last field for a look in ParaView.
    subroutine stop_run(reason)
      character(len=*), intent(in) :: reason
      character(len=24) :: step_text
      write(step_text, '(i0)') solver%step
      call output_fields()
      call fatal(scene_name//': '//reason//trim(step_text)//' (t = '//real_text(solver%time)//' s); '// &
          'the last field is in '//run_file('fields.xdmf')//'; reduce &run dt or cfl_target')
    end subroutine stop_run
  end subroutine run_scene
end module scene_loop
