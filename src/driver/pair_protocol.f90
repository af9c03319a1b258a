!> The pair protocol of the paper (section 3): a placement of two bodies (the initial condition,
!> module pair_setup) and the pair's bookkeeping in the scene loop (module scene_loop): the
!> collision events, the samples of particles.h5, the end rule and the outcome (module
!> pair_outcome), the summary, and the loop's own checkpoint group (pair_scene).
!> The paper's end is twice the first-collision time (&pair mirror_first_collision, the quiescent
!> protocol) or &pair paper_end_time (the chaotic protocol's fixed 3 ms), whichever comes first;
!> &pair end_rule = 'paper' stops there, 'settled' (default) goes on past it until the outcome is
!> settled; &run end_time caps both. Contact episodes: an impulse of a pair not yet in contact opens
!> one (an events row of particles.h5), the gap above the release gap closes it (module pair_outcome);
!> every impulse in between (the resting contact held by its impulses) counts in summary
!> collisions only.
!> Checkpoints hold the particle system (group particles, module particle_system_checkpoint) and the
!> loop's own state (group pair_scene); each is written after its step's events, sample and end
!> test, so &run restart = .true. restores both and goes on with the next particle step, bit for bit
!> (docs/outputs.md, Checkpoints).
module pair_protocol
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal
  use text_format, only: int_text
  use logger, only: log_line
  use progress_meter, only: scientific_text
  use run_directory, only: run_file
  use hdf5_files, only: h5_exists
  use hdf5_datasets, only: h5_read_scalar, h5_write_array, h5_read_array
  use checkpoint_files, only: checkpoint_t
  use particle_system_checkpoint, only: write_particle_system_checkpoint, read_particle_system_checkpoint
  use pair_setup, only: pair_t, build_pair
  use rigid_body, only: integrator_code, angular_velocity_lab
  use closest_points, only: symmetry_axis_angle
  use dlvo, only: dlvo_setup, dlvo_log_constants
  use collision, only: collision_setup, collision_log_settings, approach_speed
  use lubrication, only: lubrication_setup
  use config_grid, only: smallest_spacing
  use particle_system, only: particle_models_t, particle_loads_t, particle_system_t, particle_system_create, &
                             pair_body_image
  use agglomerate_tracking, only: agglomerate_tracker_t, agglomerate_count_contact
  use pair_outcome, only: pair_outcome_t, pair_outcome_of, pair_outcome_rules_t, pair_outcome_rules_of, pair_state_t, &
                          pair_state_of, pair_history_t, pair_history_record
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, run_summary_t, particle_output_open, &
                             particle_output_continue, particle_output_flush, particle_output_rows, &
                             append_particles_sample, append_bodies_sample, append_collision_event
  implicit none
  private
  public :: pair_loop_t, setup_system, record_interaction, run_finished, sampled, write_sample, finish_summary, &
            log_pair, write_pair_scene_group, read_pair_scene_group, normal_approach_speed, open_particle_output, &
            pair_progress_detail, particle_models_of, fluid_name, bodies_progress_detail

  !> The pair's only pair in the system's pair list.
  integer, parameter :: the_pair = 1

  !> The scene's loop state besides the particle system (kept in its checkpoints).
  type :: pair_loop_t
    real(wp) :: time = 0.0_wp                 !< s
    integer(i8) :: step = 0_i8
    real(wp) :: end_time = 0.0_wp             !< s: &run end_time, or twice the first-collision time
    real(wp) :: max_vdw_force = 0.0_wp        !< N, largest so far
    type(pair_history_t) :: history           !< the pair protocol's record for its outcome
    !> (2, k): first and second body of each pair in a contact episode now
    integer, allocatable :: contact_pairs(:,:)
  end type pair_loop_t

contains

  !> The particle system's group and the scene's own (group pair_scene) of an open checkpoint.
  subroutine write_pair_scene_group(transaction, cfg, system, loop, summary, hydrodynamic, output, last)
    type(checkpoint_t), intent(in) :: transaction
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(in) :: loop
    type(run_summary_t), intent(in) :: summary
    type(particle_loads_t), intent(in) :: hydrodynamic
    type(particle_output_t), intent(inout) :: output
    logical, intent(in) :: last          !< the finished run's last state
    integer(i8) :: rows(2)
    call particle_output_flush(output)
    call particle_output_rows(output, rows(1), rows(2))
    ! The sample a finished run adds at its last step is not kept: a continued run that goes on does
    ! not have it, one that ends there writes it again.
    if (last .and. .not. sampled(cfg, loop%step)) rows(1) = rows(1) - 1_i8
    call write_particle_system_checkpoint(transaction, system)
    associate (file => transaction%file, first => summary%first_collision)
      call h5_write_array(file, 'pair_scene/time', loop%time)
      call h5_write_array(file, 'pair_scene/step', loop%step)
      call h5_write_array(file, 'pair_scene/max_vdw_force', loop%max_vdw_force)
      call h5_write_array(file, 'pair_scene/collisions', summary%collisions)
      call h5_write_array(file, 'pair_scene/contact_episodes', summary%contact_episodes)
      ! A leading (0, 0) keeps the dataset non-empty when no pair is in contact.
      call h5_write_array(file, 'pair_scene/contact_pairs', [0, 0, reshape(held_pairs(loop), [2 * held_count(loop)])])
      call h5_write_array(file, 'pair_scene/outcome_record', [merge(1, 0, loop%history%touched), &
          merge(1, 0, loop%history%entered_range), merge(1, 0, loop%history%bound)])
      call h5_write_array(file, 'pair_scene/bound_since', loop%history%bound_since)
      call h5_write_array(file, 'pair_scene/has_first_collision', merge(1, 0, summary%has_first_collision))
      call h5_write_array(file, 'pair_scene/first_collision', [first%time, first%theta1, first%phi1, first%theta2, &
          first%phi2, first%normal_velocity_before, first%normal_velocity_after, first%psi])
      call h5_write_array(file, 'pair_scene/first_collision_bodies', [first%first, first%second])
      call h5_write_array(file, 'pair_scene/hydrodynamic_force', hydrodynamic%force)
      call h5_write_array(file, 'pair_scene/hydrodynamic_torque', hydrodynamic%torque)
      call h5_write_array(file, 'pair_scene/output_rows', rows)
    end associate
  end subroutine write_pair_scene_group

  !> From an open checkpoint: the particle system, the scene's loop, and particles.h5 continued
  !> from the checkpoint's rows.
  subroutine read_pair_scene_group(restart, cfg, system, loop, summary, hydrodynamic, output)
    type(checkpoint_t), intent(in) :: restart
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(inout) :: system
    type(pair_loop_t), intent(inout) :: loop
    type(run_summary_t), intent(inout) :: summary
    type(particle_loads_t), intent(inout) :: hydrodynamic
    type(particle_output_t), intent(out) :: output
    real(wp), allocatable :: first(:), force(:,:), torque(:,:)
    integer(i8), allocatable :: rows(:)
    integer, allocatable :: bodies(:), held(:), record(:)
    integer :: flag
    if (.not. h5_exists(restart%file, 'pair_scene/step')) call fatal('checkpoint '//restart%path// &
        ' holds no pair scene (group pair_scene): &run restart must continue a run of the same scene')
    if (.not. h5_exists(restart%file, 'pair_scene/contact_episodes')) call fatal('checkpoint '//restart%path// &
        ': its pair_scene group has no contact episodes (pair_scene/contact_episodes): written by an older '// &
        'version, it cannot be continued by this one')
    call read_particle_system_checkpoint(restart, system)
    associate (file => restart%file)
      call h5_read_scalar(file, 'pair_scene/time', loop%time)
      call h5_read_scalar(file, 'pair_scene/step', loop%step)
      call h5_read_scalar(file, 'pair_scene/max_vdw_force', loop%max_vdw_force)
      call h5_read_scalar(file, 'pair_scene/collisions', summary%collisions)
      call h5_read_scalar(file, 'pair_scene/contact_episodes', summary%contact_episodes)
      call h5_read_array(file, 'pair_scene/contact_pairs', held)
      call h5_read_array(file, 'pair_scene/outcome_record', record)
      call h5_read_scalar(file, 'pair_scene/bound_since', loop%history%bound_since)
      call h5_read_scalar(file, 'pair_scene/has_first_collision', flag)
      call h5_read_array(file, 'pair_scene/first_collision', first)
      call h5_read_array(file, 'pair_scene/first_collision_bodies', bodies)
      call h5_read_array(file, 'pair_scene/hydrodynamic_force', force)
      call h5_read_array(file, 'pair_scene/hydrodynamic_torque', torque)
      call h5_read_array(file, 'pair_scene/output_rows', rows)
    end associate
    if (size(first) /= 8 .or. size(bodies) /= 2 .or. size(rows) /= 2 .or. any(shape(force) /= [3, system%n]) .or. &
        any(shape(torque) /= [3, system%n]) .or. size(held) < 2 .or. mod(size(held), 2) /= 0 .or. &
        size(record) /= 3) call fatal('checkpoint '//restart%path// &
        ': its pair_scene group does not fit this scene (written by another version or deck?)')
    loop%contact_pairs = reshape(held(3:), [2, size(held) / 2 - 1])
    loop%history%touched = record(1) == 1
    loop%history%entered_range = record(2) == 1
    loop%history%bound = record(3) == 1
    summary%has_first_collision = (flag == 1)
    summary%first_collision = collision_event_t(time=first(1), theta1=first(2), phi1=first(3), theta2=first(4), &
        phi2=first(5), normal_velocity_before=first(6), normal_velocity_after=first(7), psi=first(8), &
        first=bodies(1), second=bodies(2))
    hydrodynamic%force = force
    hydrodynamic%torque = torque
    ! The paper's end (twice the first-collision time) as record_interaction set it, under this deck.
    loop%end_time = cfg%run%end_time
    if (summary%has_first_collision .and. mirrored(cfg)) &
      loop%end_time = min(loop%end_time, 2.0_wp * summary%first_collision%time)
    call log_line('pair scene: continuing from '//restart%path)
    call particle_output_continue(output, run_file('particles.h5'), system%n, rows(1), rows(2))
  end subroutine read_pair_scene_group

  !> A new particles.h5 in the run directory.
  subroutine open_particle_output(cfg, pair, system, output)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
    type(particle_system_t), intent(in) :: system
    type(particle_output_t), intent(out) :: output
    call particle_output_open(output, run_file('particles.h5'), pair_run_metadata_t(name=cfg%run%name, &
        shape=cfg%pair%shape, aspect_ratio=pair%shape%aspect_ratio, radius=cfg%pair%radius, fluid=fluid_name(cfg), &
        seed=int(cfg%run%seed, i8), bodies=system%n))
  end subroutine open_particle_output

  !> The fluid model of the outputs (particles.h5, summary.json): &scene fluid, and the coupling
  !> with a resolved fluid ('resolved_point'), so that batches of either are told apart.
  function fluid_name(cfg) result(name)
    type(agglo_config_t), intent(in) :: cfg
    character(len=:), allocatable :: name
    name = trim(cfg%scene%fluid)
    if (name == 'resolved') name = name//'_'//trim(cfg%scene%particle_coupling)
  end function fluid_name

  !> Is step one of the samples of particles.h5 (&output particle_interval, 0: stats_interval)?
  logical function sampled(cfg, step)
    type(agglo_config_t), intent(in) :: cfg
    integer(i8), intent(in) :: step
    integer :: interval
    interval = cfg%output%particle_interval
    if (interval == 0) interval = cfg%output%stats_interval
    sampled = mod(step, int(interval, i8)) == 0
  end function sampled

  !> The two bodies of the placed pair, their models, no box (the pair scenes are unbounded; the
  !> scene loop passes the resolved fluid's periodic box), and
  !> the placement's closest points as the current contact.
  subroutine setup_system(cfg, pair, system, box_length)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
    type(particle_system_t), intent(out) :: system
    real(wp), intent(in), optional :: box_length(3)   !< m, periodic box (the resolved fluid's); absent: unbounded
    call particle_system_create(system, [pair%shape, pair%shape], pair%body, particle_models_of(cfg), &
                                box_length=box_length, contacts=[pair%contact])
  end subroutine setup_system

  !> The particle models of the deck (&scene dlvo, collisions; &dlvo, &collision; &pair integrator,
  !> and radius for the DLVO curvature factor), their constants logged.
  function particle_models_of(cfg) result(models)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_models_t) :: models
    models%dlvo = cfg%scene%dlvo
    models%collisions = cfg%scene%collisions
    models%integrator = integrator_code(cfg%pair%integrator)
    if (models%dlvo) then
      call dlvo_setup(models%dlvo_model, cfg%dlvo, cfg%pair%radius)
      call dlvo_log_constants(models%dlvo_model)
    end if
    if (models%collisions) then
      call collision_setup(models%collision_model, cfg%collision)
      call collision_log_settings(models%collision_model)
    end if
    models%lubrication = cfg%collision%lubrication
    if (models%lubrication) call lubrication_setup(models%lubrication_model, cfg%collision, &
                                                   cfg%fluid%density * cfg%fluid%viscosity, smallest_spacing(cfg%grid))
  end function particle_models_of

  !> After an interaction: the impulses and contact episodes of every pair (an episode's first
  !> impulse is an events row; the pair protocol's first one may set the paper's end time), the
  !> largest vdW force so far and, in the pair protocol, the pair's record for its outcome.
  !> tracker (a suspension's agglomerates): each contact episode begun is counted for its species pair.
  subroutine record_interaction(cfg, system, loop, output, summary, tracker)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(inout) :: loop
    type(particle_output_t), intent(inout) :: output
    type(run_summary_t), intent(inout) :: summary
    type(agglomerate_tracker_t), intent(inout), optional :: tracker
    type(collision_event_t) :: event
    type(pair_outcome_rules_t) :: rules
    integer, allocatable :: held(:,:)
    integer :: p, kept
    logical :: was_held
    rules = pair_outcome_rules_of(system%models, cfg%pair%settle_time)
    if (.not. allocated(loop%contact_pairs)) allocate(loop%contact_pairs(2, 0))
    allocate(held(2, size(system%pairs)))
    kept = 0
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p), time => loop%time, end_time => loop%end_time, &
                 max_vdw_force => loop%max_vdw_force)
        was_held = any(loop%contact_pairs(1, :) == pair%first .and. loop%contact_pairs(2, :) == pair%second)
        if (pair%collided) then
          summary%collisions = summary%collisions + 1
          if (.not. was_held) then
            event = collision_event_t(time=time, theta1=pair%contact%theta1, phi1=pair%contact%phi1, &
                theta2=pair%contact%theta2, phi2=pair%contact%phi2, &
                normal_velocity_before=pair%collision%normal_velocity_before, &
                normal_velocity_after=pair%collision%normal_velocity_after, &
                psi=symmetry_axis_angle(system%bodies(pair%first)%quaternion, system%bodies(pair%second)%quaternion), &
                first=pair%first, second=pair%second)
            call append_collision_event(output, event)
            summary%contact_episodes = summary%contact_episodes + 1
            if (present(tracker)) call agglomerate_count_contact(tracker, pair%first, pair%second)
            if (summary%contact_episodes == 1) then
              summary%has_first_collision = .true.
              summary%first_collision = event
              if (mirrored(cfg)) end_time = min(end_time, 2.0_wp * time)
            end if
          end if
        end if
        ! In contact now: an impulse this step, or held before and not released (gap <= release gap).
        if (pair%collided .or. (was_held .and. pair%active .and. pair%contact%gap <= rules%release_gap)) then
          kept = kept + 1
          held(:, kept) = [pair%first, pair%second]
        end if
        max_vdw_force = max(max_vdw_force, abs(pair%dlvo%vdw_force))
      end associate
    end do
    loop%contact_pairs = held(:, 1:kept)
    if (cfg%scene%particles == 'pair') call pair_history_record(loop%history, current_state(rules, system), &
                                                                summary%contact_episodes > 0, loop%time)
  end subroutine record_interaction

  !> The pairs in a contact episode now, (2, k), and k.
  pure function held_pairs(loop) result(pairs)
    type(pair_loop_t), intent(in) :: loop
    integer, allocatable :: pairs(:,:)
    if (allocated(loop%contact_pairs)) then
      pairs = loop%contact_pairs
    else
      allocate(pairs(2, 0))
    end if
  end function held_pairs

  pure integer function held_count(loop)
    type(pair_loop_t), intent(in) :: loop
    held_count = 0
    if (allocated(loop%contact_pairs)) held_count = size(loop%contact_pairs, 2)
  end function held_count

  !> The paper's end at twice the first-collision time: the pair protocol's (&pair mirror_first_collision).
  logical function mirrored(cfg)
    type(agglo_config_t), intent(in) :: cfg
    mirrored = cfg%scene%particles == 'pair' .and. cfg%pair%mirror_first_collision
  end function mirrored

  !> The paper's end time: twice the first collision (loop%end_time, with &run end_time) and &pair
  !> paper_end_time when set, whichever comes first.
  real(wp) function paper_end(cfg, loop)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_loop_t), intent(in) :: loop
    paper_end = loop%end_time
    if (cfg%pair%paper_end_time > 0.0_wp) paper_end = min(paper_end, cfg%pair%paper_end_time)
  end function paper_end

  !> The end test after a step: &run end_time (the cap of every rule) or max_steps; the paper's end
  !> time (paper_end); with end_rule = 'settled', past the paper's end only once the outcome is
  !> settled.
  logical function run_finished(cfg, rules, system, loop, step)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(in) :: loop
    integer(i8), intent(in) :: step
    type(pair_outcome_t) :: outcome
    run_finished = .true.
    if (step >= cfg%run%max_steps) return
    if (loop%time >= cfg%run%end_time * (1.0_wp - 1.0e-12_wp)) return
    run_finished = loop%time >= paper_end(cfg, loop) * (1.0_wp - 1.0e-12_wp)
    if (.not. run_finished .or. cfg%pair%end_rule /= 'settled') return
    outcome = current_outcome(rules, system, loop)
    run_finished = outcome%settled
  end function run_finished

  !> The state of the pair protocol's pair now (module pair_outcome).
  type(pair_state_t) function current_state(rules, system)
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    current_state = pair_state_of(rules, system%bodies(1), pair_body_image(system, system%pairs(the_pair)), &
                                  system%pairs(the_pair)%contact, system%pairs(the_pair)%dlvo%chi_eta)
  end function current_state

  !> The outcome of the pair's current state and record (module pair_outcome).
  type(pair_outcome_t) function current_outcome(rules, system, loop)
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(in) :: loop
    current_outcome = pair_outcome_of(rules, loop%history, current_state(rules, system), loop%time)
  end function current_outcome

  !> One row of particles.h5: every body and every pair record; with bodies_layout = .true. (a
  !> suspension, whose near pairs change from step to step) every body in the bodies layout, no pairs.
  subroutine write_sample(output, time, system, hydrodynamic, bodies_layout)
    type(particle_output_t), intent(inout) :: output
    real(wp), intent(in) :: time
    type(particle_system_t), intent(in) :: system
    type(particle_loads_t), intent(in) :: hydrodynamic
    logical, intent(in), optional :: bodies_layout
    type(particle_record_t), allocatable :: records(:)
    type(pair_record_t), allocatable :: pair_records(:)
    integer :: i, p, written_pairs
    logical :: bodies
    bodies = .false.
    if (present(bodies_layout)) bodies = bodies_layout
    written_pairs = merge(0, size(system%pairs), bodies)
    allocate(records(system%n), pair_records(written_pairs))
    do i = 1, system%n
      records(i) = particle_record_t(position=system%bodies(i)%position, quaternion=system%bodies(i)%quaternion, &
          velocity=system%bodies(i)%velocity, angular_velocity=angular_velocity_lab(system%bodies(i)), &
          force_hydrodynamic=hydrodynamic%force(:, i), force_dlvo=system%dlvo_loads%force(:, i), &
          force_collision=system%collision_loads%force(:, i), torque_hydrodynamic=hydrodynamic%torque(:, i), &
          torque_dlvo=system%dlvo_loads%torque(:, i), torque_collision=system%collision_loads%torque(:, i))
    end do
    do p = 1, size(pair_records)
      associate (pair => system%pairs(p))
        pair_records(p) = pair_record_t(first=pair%first, second=pair%second, gap=pair%contact%gap, &
            closest_point1=pair%contact%point1, closest_point2=pair%contact%point2, chi_eta=pair%dlvo%chi_eta, &
            relative_velocity=normal_approach_speed(system, p), vdw_force=abs(pair%dlvo%vdw_force))
      end associate
    end do
    if (bodies) then
      call append_bodies_sample(output, time, records)
    else
      call append_particles_sample(output, time, records, pair_records)
    end if
  end subroutine write_sample

  !> Normal approach speed of the closest points of pair p, > 0 approaching.
  real(wp) function normal_approach_speed(system, p)
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: p
    associate (pair => system%pairs(p))
      normal_approach_speed = approach_speed(system%bodies(pair%first), pair_body_image(system, pair), &
                                             pair%contact%point1, pair%contact%point2, pair%contact%normal)
    end associate
  end function normal_approach_speed

  !> Free bodies: the smallest gap over the pairs and the collisions so far, for the progress log.
  function bodies_progress_detail(system, collisions) result(text)
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: collisions
    character(len=:), allocatable :: text
    integer :: p, closest
    if (size(system%pairs) == 0) then   ! a single body, or no pair near enough to interact
      text = '  bodies: '//int_text(system%n)//', no near pair  collisions = '//int_text(collisions)
      return
    end if
    closest = 1
    do p = 2, size(system%pairs)
      if (system%pairs(p)%contact%gap < system%pairs(closest)%contact%gap) closest = p
    end do
    text = '  bodies: smallest gap = '//scientific_text(system%pairs(closest)%contact%gap)//' m (bodies '// &
           int_text(system%pairs(closest)%first)//', '//int_text(system%pairs(closest)%second)//')  v_n = '// &
           scientific_text(normal_approach_speed(system, closest))//' m/s  collisions = '//int_text(collisions)
  end function bodies_progress_detail

  !> The pair's gap and normal approach speed for the progress log.
  function pair_progress_detail(system) result(text)
    type(particle_system_t), intent(in) :: system
    character(len=:), allocatable :: text
    text = '  gap = '//scientific_text(system%pairs(the_pair)%contact%gap)//' m  v_n = '// &
           scientific_text(normal_approach_speed(system, the_pair))//' m/s'
  end function pair_progress_detail

  !> The summary of the finished run; the outcome and whether it was settled (module pair_outcome,
  !> docs/theory.md "Run outcome").
  subroutine finish_summary(cfg, rules, system, loop, summary)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(in) :: loop
    type(run_summary_t), intent(inout) :: summary
    type(pair_outcome_t) :: outcome
    outcome = current_outcome(rules, system, loop)
    summary%outcome = outcome%outcome
    summary%outcome_settled = outcome%settled
    summary%ended_in_flight = .not. outcome%settled
    summary%end_rule = cfg%pair%end_rule
    summary%name = cfg%run%name
    summary%seed = int(cfg%run%seed, i8)
    summary%shape = cfg%pair%shape
    summary%aspect_ratio = system%shapes(1)%aspect_ratio
    summary%fluid = fluid_name(cfg)
    summary%max_vdw_force = loop%max_vdw_force
    summary%final_gap = system%pairs(the_pair)%contact%gap
    summary%final_relative_velocity = normal_approach_speed(system, the_pair)
    summary%psi_final = symmetry_axis_angle(system%bodies(1)%quaternion, system%bodies(2)%quaternion)
    summary%end_time = loop%time
    summary%steps = loop%step
  end subroutine finish_summary

  subroutine log_pair(cfg, pair, rules)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
    type(pair_outcome_rules_t), intent(in) :: rules
    character(len=240) :: line
    write(line, '(a,a,a,es11.4,a,es11.4,a,es11.4,a,es11.4,a)') 'pair: shape ''', trim(cfg%pair%shape), ''', a = ', &
        pair%shape%a, ' m, b = ', pair%shape%b, ' m (a/b = ', pair%shape%aspect_ratio, '), mass = ', pair%shape%mass, ' kg'
    call log_line(trim(line))
    write(line, '(a,es12.5,a,3f9.5,a,f8.4,a)') 'pair: placed with gap ', pair%contact%gap, ' m along n = (', &
        pair%contact%normal, '), psi = ', symmetry_axis_angle(pair%body(1)%quaternion, pair%body(2)%quaternion), ' rad'
    call log_line(trim(line))
    write(line, '(a,es11.4,a,a,a,es10.3,a,es11.4,a)') 'pair: relative speed ', cfg%pair%relative_speed, &
        ' m/s; fluid ''', trim(cfg%scene%fluid), '''; dt = ', cfg%run%dt, ' s; end time ', cfg%run%end_time, ' s'
    call log_line(trim(line))
    write(line, '(a,a,a,es10.3,a,es10.3,a,es10.3,a)') 'pair: end rule ''', trim(cfg%pair%end_rule), &
        '''; outcome: DLVO range ', rules%dlvo_range, ' m, settled when bound for ', rules%settle_time, &
        ' s; a contact episode ends above a gap of ', rules%release_gap, ' m'
    call log_line(trim(line))
  end subroutine log_pair

end module pair_protocol
