!> The particle-pair scenes without a grid: fluid = 'none' (vacuum) or 'stokes' (each spheroid
!> feels the drag and torque of its analytic resistance tensors in quiescent fluid).
!> The pair is a particle system of two bodies (module particle_system): each step is one
!> particle_system_step under the Stokes loads of the current state (frozen over the step), which
!> leaves the system current (closest points, collision impulses, DLVO loads), then the collision
!> events, the output sample and the end test. The run ends at &run end_time, or at twice the
!> first-collision time (&pair mirror_first_collision, the paper's protocol), and with
!> &pair end_rule = 'settled' not before the outcome is settled (module pair_outcome), at most at
!> &run end_time.
module pair_scene
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  use wall_clock, only: wall_time
  use progress_meter, only: progress_meter_t, progress_report, scientific_text
  use run_directory, only: run_file
  use pair_setup, only: pair_t, build_pair
  use rigid_body, only: integrator_code, angular_velocity_lab
  use closest_points, only: symmetry_axis_angle
  use dlvo, only: dlvo_setup, dlvo_log_constants
  use collision, only: collision_setup, collision_log_settings, approach_speed
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_of, stokes_loads
  use particle_system, only: particle_models_t, particle_loads_t, particle_system_t, particle_system_create, &
                             particle_system_interact, particle_system_step, particle_loads_zero, pair_body_image
  use pair_outcome, only: pair_outcome_t, pair_outcome_of, pair_outcome_rules_t, pair_outcome_rules_of
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, run_summary_t, particle_output_open, particle_output_close, &
                             append_particles_sample, append_collision_event, write_summary_json
  implicit none
  private
  public :: run_pair_scene

  !> The pair's only pair in the system's pair list.
  integer, parameter :: the_pair = 1

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
    real(wp) :: time, dt, end_time, wall_start, max_vdw_force
    integer(i8) :: step
    logical :: stokes, finished

    call build_pair(cfg%pair, cfg%run%seed, pair)
    call setup_system(cfg, pair, system)
    stokes = (cfg%scene%fluid == 'stokes')
    if (stokes) resistance = stokes_resistance_of(pair%shape, cfg%fluid%density * cfg%fluid%viscosity)
    rules = pair_outcome_rules_of(system%models)
    call log_pair(cfg, pair, rules)
    call particle_output_open(output, run_file('particles.h5'), pair_run_metadata_t(name=cfg%run%name, &
        shape=cfg%pair%shape, aspect_ratio=pair%shape%aspect_ratio, radius=cfg%pair%radius, fluid=cfg%scene%fluid, &
        seed=int(cfg%run%seed, i8), bodies=system%n))

    dt = cfg%run%dt
    end_time = cfg%run%end_time
    time = 0.0_wp
    step = 0_i8
    max_vdw_force = 0.0_wp
    summary%collisions = 0
    wall_start = wall_time()
    hydrodynamic = particle_loads_zero(system%n)
    ! The collision test comes first, on the current state: with a detection distance of
    ! v_n dt the pair is caught before a step could carry it into overlap.
    call particle_system_interact(system, dt)
    finished = .false.
    do
      call record_interaction(cfg, system, time, output, summary, end_time, max_vdw_force)
      if (stokes) call stokes_loads_of(resistance, system, hydrodynamic)
      if (step > 0) finished = run_finished(cfg, rules, system, summary, time, step, end_time)
      if (mod(step, int(cfg%output%stats_interval, i8)) == 0 .or. finished) &
        call write_sample(output, time, system, hydrodynamic)
      if (step > 0 .and. (mod(step, int(cfg%run%progress_interval, i8)) == 0 .or. finished)) &
        call progress_line(step, time, dt, end_time, system, wall_time() - wall_start)
      if (finished) exit
      call particle_system_step(system, dt, hydrodynamic)   ! zero at fluid = 'none'
      time = time + dt
      step = step + 1
    end do
    call particle_output_close(output)

    call finish_summary(cfg, rules, system, time, step, max_vdw_force, wall_time() - wall_start, summary)
    call write_summary_json(run_file('summary.json'), summary)
    call log_line('pair scene: outcome '//trim(summary%outcome)//'; particles.h5 and summary.json written')
  end subroutine run_pair_scene

  !> The two bodies of the placed pair, their models, no box (the pair scenes are unbounded), and
  !> the placement's closest points as the current contact.
  subroutine setup_system(cfg, pair, system)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
    type(particle_system_t), intent(out) :: system
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
    call particle_system_create(system, [pair%shape, pair%shape], pair%body, models, contacts=[pair%contact])
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
  subroutine record_interaction(cfg, system, time, output, summary, end_time, max_vdw_force)
    type(agglo_config_t), intent(in) :: cfg
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: time
    type(particle_output_t), intent(inout) :: output
    type(run_summary_t), intent(inout) :: summary
    real(wp), intent(inout) :: end_time, max_vdw_force
    type(collision_event_t) :: event
    associate (pair => system%pairs(the_pair))
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

  !> The progress line (core progress_meter) with the pair's gap and normal approach speed.
  subroutine progress_line(step, time, dt, end_time, system, elapsed)
    integer(i8), intent(in) :: step
    real(wp), intent(in) :: time, dt, end_time, elapsed
    type(particle_system_t), intent(in) :: system
    type(progress_meter_t), save :: meter
    call log_line(progress_report(meter, wall_time(), step, time, dt, elapsed / real(step, wp), end_time - time, &
                                  detail='  gap = '//scientific_text(system%pairs(the_pair)%contact%gap)//' m  v_n = '// &
                                  scientific_text(normal_approach_speed(system, the_pair))//' m/s'))
  end subroutine progress_line

  !> The summary of the finished run; the outcome and whether it was settled (module pair_outcome,
  !> docs/theory.md "Run outcome").
  subroutine finish_summary(cfg, rules, system, time, step, max_vdw_force, wall, summary)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_outcome_rules_t), intent(in) :: rules
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: time, max_vdw_force, wall
    integer(i8), intent(in) :: step
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
    summary%fluid = cfg%scene%fluid
    summary%max_vdw_force = max_vdw_force
    summary%final_gap = system%pairs(the_pair)%contact%gap
    summary%final_relative_velocity = normal_approach_speed(system, the_pair)
    summary%psi_final = symmetry_axis_angle(system%bodies(1)%quaternion, system%bodies(2)%quaternion)
    summary%end_time = time
    summary%steps = step
    summary%wall_time = wall
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
