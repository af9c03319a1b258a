!> The particle-pair scenes without a grid: fluid = 'none' (vacuum) or 'stokes' (each spheroid
!> feels the drag and torque of its analytic resistance tensors in quiescent fluid).
!> The pair is a particle system of two bodies (module particle_system): each step is one
!> particle_system_step under the Stokes loads of the current state (frozen over the step), which
!> leaves the system current (closest points, collision impulses, DLVO loads), then the collision
!> events, the output sample and the end test. The run ends at &run end_time, or at twice the
!> first-collision time (&pair mirror_first_collision, the paper's protocol), and with
!> &pair end_rule = 'settled' not before the outcome is settled (module pair_outcome), at most at
!> &run end_time.
!> Checkpoints (every &output checkpoint_interval steps and at the end) hold the particle system
!> (group particles, module particle_system_checkpoint) and the loop's own state (group pair_scene);
!> each is written after its step's events, sample and end test, so &run restart = .true. restores
!> both and goes on with the next particle step, bit for bit (docs/outputs.md, Checkpoints).
!> The pair's bookkeeping (system set-up, collision events, samples, end test, summary, checkpoint
!> group) is public: the pair in the resolved fluid (module resolved_pair_scene) keeps it the same way.
module pair_scene
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use logger, only: log_line
  use text_format, only: int_text, real_text
  use wall_clock, only: wall_time
  use progress_meter, only: progress_meter_t, progress_report, scientific_text
  use run_directory, only: run_file
  use hdf5_files, only: h5_exists
  use hdf5_datasets, only: h5_read_scalar, h5_write_array, h5_read_array
  use checkpoint_files, only: checkpoint_t, checkpoint_begin, checkpoint_commit, checkpoint_open_newest, checkpoint_close
  use particle_system_checkpoint, only: write_particle_system_checkpoint, read_particle_system_checkpoint
  use fluid_monitor, only: timing_report
  use pair_setup, only: pair_t, build_pair
  use rigid_body, only: integrator_code, angular_velocity_lab
  use closest_points, only: symmetry_axis_angle
  use dlvo, only: dlvo_setup, dlvo_log_constants
  use collision, only: collision_setup, collision_log_settings, approach_speed
  use lubrication, only: lubrication_setup
  use config_grid, only: smallest_spacing
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_of, stokes_loads
  use particle_system, only: particle_models_t, particle_loads_t, particle_system_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero, pair_body_image
  use pair_outcome, only: pair_outcome_t, pair_outcome_of, pair_outcome_rules_t, pair_outcome_rules_of
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, run_summary_t, particle_output_open, particle_output_close, &
                             particle_output_continue, particle_output_flush, particle_output_rows, &
                             append_particles_sample, append_collision_event, write_summary_json
  implicit none
  private
  public :: run_pair_scene
  ! Shared with the pair in the resolved fluid (module resolved_pair_scene): the pair's bookkeeping.
  public :: pair_loop_t, setup_system, record_interaction, run_finished, sampled, write_sample, finish_summary, &
            log_pair, write_pair_scene_group, read_pair_scene_group, normal_approach_speed, open_particle_output

  !> The pair's only pair in the system's pair list.
  integer, parameter :: the_pair = 1

  !> The scene's loop state besides the particle system (kept in its checkpoints).
  type :: pair_loop_t
    real(wp) :: time = 0.0_wp                 !< s
    integer(i8) :: step = 0_i8
    real(wp) :: end_time = 0.0_wp             !< s: &run end_time, or twice the first-collision time
    real(wp) :: max_vdw_force = 0.0_wp        !< N, largest so far
  end type pair_loop_t

contains

  subroutine run_pair_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t) :: pair
    type(particle_system_t) :: system
    type(stokes_resistance_t) :: resistance
    type(particle_loads_t) :: hydrodynamic
    type(pair_outcome_rules_t) :: rules
    type(particle_output_t) :: output
    type(run_summary_t) :: summary
    type(pair_loop_t) :: loop
    real(wp) :: dt, wall_start
    integer(i8) :: first_step
    integer :: timer_step
    logical :: stokes, finished, resumed

    call build_pair(cfg%pair, cfg%run%seed, pair)
    call setup_system(cfg, pair, system)
    stokes = (cfg%scene%fluid == 'stokes')
    if (stokes) resistance = stokes_resistance_of(pair%shape, cfg%fluid%density * cfg%fluid%viscosity)
    rules = pair_outcome_rules_of(system%models)
    call log_pair(cfg, pair, rules)
    timer_step = timer_register('particle step')

    dt = cfg%run%dt
    loop%end_time = cfg%run%end_time
    summary%collisions = 0
    hydrodynamic = particle_loads_zero(system%n)
    resumed = cfg%run%restart
    if (resumed) then
      call restore_pair_scene(cfg, system, loop, summary, hydrodynamic, output)
    else
      call open_particle_output(cfg, pair, system, output)
      ! The collision test comes first, on the current state: with a detection distance of
      ! v_n dt the pair is caught before a step could carry it into overlap.
      call particle_system_interact(system, dt)
    end if
    first_step = loop%step
    wall_start = wall_time()
    finished = .false.
    do
      if (resumed) then
        ! The checkpoint was written after this step's events, sample and end test: only the end
        ! test is repeated (the deck of the continued run may set a later end).
        resumed = .false.
        finished = loop%step > 0 .and. run_finished(cfg, rules, system, summary, loop%time, loop%step, loop%end_time)
        if (finished .and. .not. sampled(cfg, loop%step)) call write_sample(output, loop%time, system, hydrodynamic)
      else
        call record_interaction(cfg, system, loop, output, summary)
        if (stokes) call stokes_loads_of(resistance, system, hydrodynamic)
        ! &pair hydrodynamics_from = 'first_contact': no hydrodynamic loads before the first collision.
        if (cfg%pair%hydrodynamics_from == 'first_contact' .and. summary%collisions == 0) &
          hydrodynamic = particle_loads_zero(system%n)
        if (loop%step > 0) finished = run_finished(cfg, rules, system, summary, loop%time, loop%step, loop%end_time)
        if (sampled(cfg, loop%step) .or. finished) &
          call write_sample(output, loop%time, system, hydrodynamic)
        if (loop%step > first_step .and. (mod(loop%step, int(cfg%run%progress_interval, i8)) == 0 .or. finished)) &
          call progress_line(loop%step - first_step, loop, dt, system, wall_time() - wall_start, &
                           cfg%run%max_steps)
        if (.not. finished .and. loop%step > first_step .and. cfg%output%checkpoint_interval > 0) then
          if (mod(loop%step, int(cfg%output%checkpoint_interval, i8)) == 0) &
            call checkpoint_pair_scene(cfg, system, loop, summary, hydrodynamic, output, last=.false.)
        end if
      end if
      if (finished) exit
      call timer_tic(timer_step)
      call particle_system_step(system, dt, hydrodynamic)   ! zero at fluid = 'none'
      call timer_toc(timer_step)
      loop%time = loop%time + dt
      loop%step = loop%step + 1
    end do
    ! The last state is always kept (checkpoint_interval = 0: only there; the loop writes none at the
    ! end), so a finished run can be continued with a later &run end_time.
    if (loop%step > first_step) call checkpoint_pair_scene(cfg, system, loop, summary, hydrodynamic, output, last=.true.)
    call particle_output_close(output)

    call finish_summary(cfg, rules, system, loop, summary)
    summary%wall_time = wall_time() - wall_start
    call write_summary_json(run_file('summary.json'), summary)
    call timing_report(loop%step - first_step, wall_time() - wall_start)
    call log_line('pair scene: outcome '//trim(summary%outcome)//'; particles.h5 and summary.json written')
    if (loop%step >= cfg%run%max_steps .and. loop%time < loop%end_time * (1.0_wp - 1.0e-12_wp)) &
      call log_line('pair scene: stopped by &run max_steps = '//int_text(cfg%run%max_steps)//' at t = '// &
                    real_text(loop%time)//' s, before the end time '//real_text(loop%end_time)//' s')
  end subroutine run_pair_scene

  !> One checkpoint transaction: the particle system's group and the scene's own (group pair_scene:
  !> time, step, the largest vdW force, the collision count and first collision, the Stokes loads the
  !> next step is taken under, and the rows of particles.h5, flushed to disk first).
  subroutine checkpoint_pair_scene(cfg, system, loop, summary, hydrodynamic, output, last)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(in) :: loop
    type(run_summary_t), intent(in) :: summary
    type(particle_loads_t), intent(in) :: hydrodynamic
    type(particle_output_t), intent(inout) :: output
    logical, intent(in) :: last          !< the finished run's last state
    type(checkpoint_t) :: transaction
    call checkpoint_begin(transaction, loop%step)
    call write_pair_scene_group(transaction, cfg, system, loop, summary, hydrodynamic, output, last)
    call checkpoint_commit(transaction, cfg%output%checkpoints_kept)
  end subroutine checkpoint_pair_scene

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
      call h5_write_array(file, 'pair_scene/has_first_collision', merge(1, 0, summary%has_first_collision))
      call h5_write_array(file, 'pair_scene/first_collision', [first%time, first%theta1, first%phi1, first%theta2, &
          first%phi2, first%normal_velocity_before, first%normal_velocity_after, first%psi])
      call h5_write_array(file, 'pair_scene/first_collision_bodies', [first%first, first%second])
      call h5_write_array(file, 'pair_scene/hydrodynamic_force', hydrodynamic%force)
      call h5_write_array(file, 'pair_scene/hydrodynamic_torque', hydrodynamic%torque)
      call h5_write_array(file, 'pair_scene/output_rows', rows)
    end associate
  end subroutine write_pair_scene_group

  !> &run restart: the newest valid checkpoint restores the particle system and the scene's loop
  !> (the system is current: no new interaction), and particles.h5 continues from its rows.
  subroutine restore_pair_scene(cfg, system, loop, summary, hydrodynamic, output)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(inout) :: system
    type(pair_loop_t), intent(inout) :: loop
    type(run_summary_t), intent(inout) :: summary
    type(particle_loads_t), intent(inout) :: hydrodynamic
    type(particle_output_t), intent(out) :: output
    type(checkpoint_t) :: restart
    call checkpoint_open_newest(restart)
    call read_pair_scene_group(restart, cfg, system, loop, summary, hydrodynamic, output)
    call checkpoint_close(restart)
  end subroutine restore_pair_scene

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
    integer, allocatable :: bodies(:)
    integer :: flag
    if (.not. h5_exists(restart%file, 'pair_scene/step')) call fatal('checkpoint '//restart%path// &
        ' holds no pair scene (group pair_scene): &run restart must continue a run of the same scene')
    call read_particle_system_checkpoint(restart, system)
    associate (file => restart%file)
      call h5_read_scalar(file, 'pair_scene/time', loop%time)
      call h5_read_scalar(file, 'pair_scene/step', loop%step)
      call h5_read_scalar(file, 'pair_scene/max_vdw_force', loop%max_vdw_force)
      call h5_read_scalar(file, 'pair_scene/collisions', summary%collisions)
      call h5_read_scalar(file, 'pair_scene/has_first_collision', flag)
      call h5_read_array(file, 'pair_scene/first_collision', first)
      call h5_read_array(file, 'pair_scene/first_collision_bodies', bodies)
      call h5_read_array(file, 'pair_scene/hydrodynamic_force', force)
      call h5_read_array(file, 'pair_scene/hydrodynamic_torque', torque)
      call h5_read_array(file, 'pair_scene/output_rows', rows)
    end associate
    if (size(first) /= 8 .or. size(bodies) /= 2 .or. size(rows) /= 2 .or. any(shape(force) /= [3, system%n]) .or. &
        any(shape(torque) /= [3, system%n])) call fatal('checkpoint '//restart%path// &
        ': its pair_scene group does not fit this scene (written by another version or deck?)')
    summary%has_first_collision = (flag == 1)
    summary%first_collision = collision_event_t(time=first(1), theta1=first(2), phi1=first(3), theta2=first(4), &
        phi2=first(5), normal_velocity_before=first(6), normal_velocity_after=first(7), psi=first(8), &
        first=bodies(1), second=bodies(2))
    hydrodynamic%force = force
    hydrodynamic%torque = torque
    ! The paper's end (twice the first-collision time) as record_interaction set it, under this deck.
    loop%end_time = cfg%run%end_time
    if (summary%has_first_collision .and. cfg%pair%mirror_first_collision) &
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

  !> Is step one of the &output stats_interval samples?
  logical function sampled(cfg, step)
    type(agglo_config_t), intent(in) :: cfg
    integer(i8), intent(in) :: step
    sampled = mod(step, int(cfg%output%stats_interval, i8)) == 0
  end function sampled

  !> The two bodies of the placed pair, their models, no box (the pair scenes are unbounded; the
  !> resolved pair scene passes the fluid's periodic box), and
  !> the placement's closest points as the current contact.
  subroutine setup_system(cfg, pair, system, box_length)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
    type(particle_system_t), intent(out) :: system
    real(wp), intent(in), optional :: box_length(3)   !< m, periodic box (the resolved fluid's); absent: unbounded
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
    call particle_system_create(system, [pair%shape, pair%shape], pair%body, models, box_length=box_length, &
                                contacts=[pair%contact])
  end subroutine setup_system

  !> Stokes drag and torque of each body at its current velocities (lab frame).
  subroutine stokes_loads_of(resistance, system, loads)
    type(stokes_resistance_t), intent(in) :: resistance
    type(particle_system_t), intent(in) :: system
    type(particle_loads_t), intent(inout) :: loads
    integer :: i
    do i = 1, system%n
      call stokes_loads(resistance, system%bodies(i), loads%force(:, i), loads%torque(:, i))
    end do
  end subroutine stokes_loads_of

  !> After an interaction: the collision events (the first one may set the paper's end time) and the
  !> largest vdW force so far.
  subroutine record_interaction(cfg, system, loop, output, summary)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(inout) :: loop
    type(particle_output_t), intent(inout) :: output
    type(run_summary_t), intent(inout) :: summary
    type(collision_event_t) :: event
    associate (pair => system%pairs(the_pair), time => loop%time, end_time => loop%end_time, &
               max_vdw_force => loop%max_vdw_force)
      if (pair%collided) then
        event = collision_event_t(time=time, theta1=pair%contact%theta1, phi1=pair%contact%phi1, &
            theta2=pair%contact%theta2, phi2=pair%contact%phi2, &
            normal_velocity_before=pair%collision%normal_velocity_before, &
            normal_velocity_after=pair%collision%normal_velocity_after, &
            psi=symmetry_axis_angle(system%bodies(1)%quaternion, system%bodies(2)%quaternion), &
            first=pair%first, second=pair%second)
        call append_collision_event(output, event)
        summary%collisions = summary%collisions + 1
        if (summary%collisions == 1) then
          summary%has_first_collision = .true.
          summary%first_collision = event
          if (cfg%pair%mirror_first_collision) end_time = min(end_time, 2.0_wp * time)
        end if
      end if
      max_vdw_force = max(max_vdw_force, abs(pair%dlvo%vdw_force))
    end associate
  end subroutine record_interaction

  !> The end test after a step: the paper's end time (end_time: &run end_time, or twice the first
  !> collision) or &run max_steps; with end_rule = 'settled', past the paper's end time only once the
  !> outcome is settled or at &run end_time (the cap).
  logical function run_finished(cfg, rules, system, summary, time, step, end_time)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    type(run_summary_t), intent(in) :: summary
    real(wp), intent(in) :: time, end_time
    integer(i8), intent(in) :: step
    type(pair_outcome_t) :: outcome
    run_finished = .true.
    if (step >= cfg%run%max_steps) return
    if (time >= cfg%run%end_time * (1.0_wp - 1.0e-12_wp)) return
    run_finished = time >= end_time * (1.0_wp - 1.0e-12_wp)
    if (.not. run_finished .or. cfg%pair%end_rule /= 'settled') return
    outcome = current_outcome(rules, system, summary)
    run_finished = outcome%settled
  end function run_finished

  !> The outcome of the pair's current state (module pair_outcome).
  type(pair_outcome_t) function current_outcome(rules, system, summary)
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    type(run_summary_t), intent(in) :: summary
    current_outcome = pair_outcome_of(rules, summary%collisions > 0, system%bodies(1), &
        pair_body_image(system, system%pairs(the_pair)), system%pairs(the_pair)%contact, &
        system%pairs(the_pair)%dlvo%chi_eta)
  end function current_outcome

  subroutine write_sample(output, time, system, hydrodynamic)
    type(particle_output_t), intent(inout) :: output
    real(wp), intent(in) :: time
    type(particle_system_t), intent(in) :: system
    type(particle_loads_t), intent(in) :: hydrodynamic
    type(particle_record_t) :: records(system%n)
    type(pair_record_t) :: pair_records(size(system%pairs))
    integer :: i, p
    do i = 1, system%n
      records(i) = particle_record_t(position=system%bodies(i)%position, quaternion=system%bodies(i)%quaternion, &
          velocity=system%bodies(i)%velocity, angular_velocity=angular_velocity_lab(system%bodies(i)), &
          force_hydrodynamic=hydrodynamic%force(:, i), force_dlvo=system%dlvo_loads%force(:, i), &
          force_collision=system%collision_loads%force(:, i), torque_hydrodynamic=hydrodynamic%torque(:, i), &
          torque_dlvo=system%dlvo_loads%torque(:, i), torque_collision=system%collision_loads%torque(:, i))
    end do
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p))
        pair_records(p) = pair_record_t(first=pair%first, second=pair%second, gap=pair%contact%gap, &
            closest_point1=pair%contact%point1, closest_point2=pair%contact%point2, chi_eta=pair%dlvo%chi_eta, &
            relative_velocity=normal_approach_speed(system, p), vdw_force=abs(pair%dlvo%vdw_force))
      end associate
    end do
    call append_particles_sample(output, time, records, pair_records)
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

  !> The progress line (core progress_meter) with the pair's gap and normal approach speed;
  !> steps_taken: steps of this run segment (since the start or the restart), for the speed;
  !> max_steps: &run max_steps, for the ETA when the run stops there before its end time.
  subroutine progress_line(steps_taken, loop, dt, system, elapsed, max_steps)
    integer(i8), intent(in) :: steps_taken
    type(pair_loop_t), intent(in) :: loop
    real(wp), intent(in) :: dt, elapsed
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: max_steps
    type(progress_meter_t), save :: meter
    call log_line(progress_report(meter, wall_time(), loop%step, loop%time, dt, elapsed / real(steps_taken, wp), &
                                  loop%end_time - loop%time, steps_left=real(max_steps - loop%step, wp), &
                                  detail='  gap = '//scientific_text(system%pairs(the_pair)%contact%gap)//' m  v_n = '// &
                                  scientific_text(normal_approach_speed(system, the_pair))//' m/s'))
  end subroutine progress_line

  !> The summary of the finished run; the outcome and whether it was settled (module pair_outcome,
  !> docs/theory.md "Run outcome").
  subroutine finish_summary(cfg, rules, system, loop, summary)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    type(pair_loop_t), intent(in) :: loop
    type(run_summary_t), intent(inout) :: summary
    type(pair_outcome_t) :: outcome
    outcome = current_outcome(rules, system, summary)
    summary%outcome = outcome%outcome
    summary%outcome_settled = outcome%settled
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
    write(line, '(a,a,a,es10.3,a,es10.3,a)') 'pair: end rule ''', trim(cfg%pair%end_rule), &
        '''; outcome: in contact below a gap of ', rules%contact_gap, ' m, DLVO range ', rules%dlvo_range, ' m'
    call log_line(trim(line))
  end subroutine log_pair

end module pair_scene
