!> The particle-pair scenes without a grid: fluid = 'none' (vacuum) or 'stokes' (each spheroid
!> feels the drag and torque of its analytic resistance tensors in quiescent fluid).
!> One step: loads (Stokes, DLVO at the closest points) -> rigid-body update -> closest points
!> (warm start) -> collision test and impulse -> output. The run ends at &run end_time, or at
!> twice the first-collision time (&pair mirror_first_collision, the paper's protocol).
module pair_scene
  use agglo_kinds, only: wp, i8
  use vector_algebra, only: cross
  use agglo_config, only: agglo_config_t
  use error_handling, only: fatal
  use logger, only: log_line
  use wall_clock, only: wall_time
  use progress_meter, only: progress_meter_t, progress_report, scientific_text
  use run_directory, only: run_file
  use pair_setup, only: pair_t, build_pair
  use rigid_body, only: rigid_body_step, integrator_code, angular_velocity_lab
  use closest_points, only: closest_points_t, find_closest_points, symmetry_axis_angle
  use dlvo, only: dlvo_model_t, dlvo_setup, dlvo_log_constants, dlvo_evaluation_t, dlvo_evaluate, &
                  relative_normal_energy, escape_energy
  use collision, only: collision_model_t, collision_result_t, collision_setup, collision_log_settings, &
                       collision_detected, collide, approach_speed
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_of, stokes_loads
  use particle_output, only: particle_output_t, pair_run_metadata_t, particle_record_t, pair_record_t, &
                             collision_event_t, run_summary_t, particle_output_open, particle_output_close, &
                             append_pair_sample, append_collision_event, write_summary_json
  implicit none
  private
  public :: run_pair_scene

  !> Loads on both particles by kind (lab frame; torques about each centre).
  type :: pair_loads_t
    real(wp) :: force_hydrodynamic(3, 2) = 0.0_wp, torque_hydrodynamic(3, 2) = 0.0_wp
    real(wp) :: force_dlvo(3, 2) = 0.0_wp, torque_dlvo(3, 2) = 0.0_wp
    real(wp) :: force_collision(3, 2) = 0.0_wp, torque_collision(3, 2) = 0.0_wp
    real(wp) :: chi_eta = 1.0_wp, vdw_force = 0.0_wp
  end type pair_loads_t

  !> Everything the scene's models need, set up once.
  type :: pair_models_t
    logical :: stokes = .false., dlvo = .false., collisions = .false.
    type(stokes_resistance_t) :: resistance
    type(dlvo_model_t) :: dlvo_model
    type(collision_model_t) :: collision_model
    integer :: integrator = 0
  end type pair_models_t

contains

  subroutine run_pair_scene(cfg)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t) :: pair
    type(pair_models_t) :: models
    type(pair_loads_t) :: loads
    type(particle_output_t) :: output
    type(run_summary_t) :: summary
    type(collision_event_t) :: event
    real(wp) :: time, dt, end_time, wall_start, max_vdw_force
    integer(i8) :: step
    logical :: finished

    call build_pair(cfg%pair, cfg%run%seed, pair)
    call setup_models(cfg, pair, models)
    call log_pair(cfg, pair)
    call particle_output_open(output, run_file('particles.h5'), pair_run_metadata_t(name=cfg%run%name, &
        shape=cfg%pair%shape, aspect_ratio=pair%shape%aspect_ratio, radius=cfg%pair%radius, fluid=cfg%scene%fluid, &
        seed=int(cfg%run%seed, i8)))

    dt = cfg%run%dt
    end_time = cfg%run%end_time
    time = 0.0_wp
    step = 0_i8
    max_vdw_force = 0.0_wp
    summary%collisions = 0
    wall_start = wall_time()
    finished = .false.
    do
      ! The collision test comes first, on the current state: with a detection distance of
      ! v_n dt the pair is caught before a step could carry it into overlap.
      loads%force_collision = 0.0_wp
      loads%torque_collision = 0.0_wp
      if (models%collisions) then
        if (collision_detected(models%collision_model, pair%body(1), pair%body(2), pair%contact, dt)) then
          call resolve_collision(models, pair, time, dt, loads, event)
          call append_collision_event(output, event)
          summary%collisions = summary%collisions + 1
          if (summary%collisions == 1) then
            summary%has_first_collision = .true.
            summary%first_collision = event
            if (cfg%pair%mirror_first_collision) end_time = min(end_time, 2.0_wp * time)
          end if
        end if
      end if
      call evaluate_loads(models, pair, loads)
      max_vdw_force = max(max_vdw_force, abs(loads%vdw_force))
      if (mod(step, int(cfg%output%stats_interval, i8)) == 0 .or. finished) call write_sample(output, time, pair, loads)
      if (step > 0 .and. (mod(step, int(cfg%run%progress_interval, i8)) == 0 .or. finished)) &
        call progress_line(step, time, dt, end_time, pair, wall_time() - wall_start)
      if (finished) exit
      call advance(models, pair, loads, dt)
      time = time + dt
      step = step + 1
      finished = time >= end_time * (1.0_wp - 1.0e-12_wp) .or. step >= cfg%run%max_steps
    end do
    call particle_output_close(output)

    call finish_summary(cfg, models, pair, loads, time, step, max_vdw_force, wall_time() - wall_start, summary)
    call write_summary_json(run_file('summary.json'), summary)
    call log_line('pair scene: outcome '//trim(summary%outcome)//'; particles.h5 and summary.json written')
  end subroutine run_pair_scene

  subroutine setup_models(cfg, pair, models)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
    type(pair_models_t), intent(out) :: models
    models%stokes = (cfg%scene%fluid == 'stokes')
    if (models%stokes) models%resistance = stokes_resistance_of(pair%shape, cfg%fluid%density * cfg%fluid%viscosity)
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
  end subroutine setup_models

  !> Loads at the current state; the closest points (pair%contact) are current.
  subroutine evaluate_loads(models, pair, loads)
    type(pair_models_t), intent(in) :: models
    type(pair_t), intent(in) :: pair
    type(pair_loads_t), intent(inout) :: loads
    type(dlvo_evaluation_t) :: evaluation
    integer :: i
    if (models%stokes) then
      do i = 1, 2
        call stokes_loads(models%resistance, pair%body(i), loads%force_hydrodynamic(:, i), loads%torque_hydrodynamic(:, i))
      end do
    end if
    if (models%dlvo) then
      call dlvo_evaluate(models%dlvo_model, pair%shape, pair%body(1), pair%shape, pair%body(2), pair%contact, evaluation)
      loads%force_dlvo(:, 1) = evaluation%force1
      loads%force_dlvo(:, 2) = evaluation%force2
      loads%torque_dlvo(:, 1) = evaluation%torque1
      loads%torque_dlvo(:, 2) = evaluation%torque2
      loads%chi_eta = evaluation%chi_eta
      loads%vdw_force = evaluation%vdw_force
    end if
  end subroutine evaluate_loads

  !> Newton-Euler update of both bodies under the current loads, then the new closest points.
  subroutine advance(models, pair, loads, dt)
    type(pair_models_t), intent(in) :: models
    type(pair_t), intent(inout) :: pair
    type(pair_loads_t), intent(in) :: loads
    real(wp), intent(in) :: dt
    integer :: i
    do i = 1, 2
      call rigid_body_step(pair%body(i), loads%force_hydrodynamic(:, i) + loads%force_dlvo(:, i), &
                           loads%torque_hydrodynamic(:, i) + loads%torque_dlvo(:, i), dt, models%integrator)
    end do
    call update_contact(pair)
  end subroutine advance

  subroutine update_contact(pair)
    type(pair_t), intent(inout) :: pair
    type(closest_points_t) :: previous   ! warm start (a copy: the result overwrites pair%contact)
    previous = pair%contact
    call find_closest_points(pair%shape, pair%body(1)%position, pair%body(1)%quaternion, pair%shape, &
                             pair%body(2)%position, pair%body(2)%quaternion, pair%contact, previous=previous)
    if (.not. pair%contact%converged) call fatal('pair scene: closest points did not converge: '// &
                                                 trim(pair%contact%message))
  end subroutine update_contact

  !> Impulse at the closest points; the collision force of the outputs is the impulse over dt
  !> (paper, Eq. 17), applied at the contact point.
  subroutine resolve_collision(models, pair, time, dt, loads, event)
    type(pair_models_t), intent(in) :: models
    type(pair_t), intent(inout) :: pair
    real(wp), intent(in) :: time, dt
    type(pair_loads_t), intent(inout) :: loads
    type(collision_event_t), intent(out) :: event
    type(collision_result_t) :: result
    call collide(models%collision_model, pair%body(1), pair%body(2), pair%contact, result)
    loads%force_collision(:, 1) = -result%impulse / dt
    loads%force_collision(:, 2) = result%impulse / dt
    loads%torque_collision(:, 1) = cross(result%contact_point - pair%body(1)%position, loads%force_collision(:, 1))
    loads%torque_collision(:, 2) = cross(result%contact_point - pair%body(2)%position, loads%force_collision(:, 2))
    event = collision_event_t(time=time, theta1=pair%contact%theta1, phi1=pair%contact%phi1, theta2=pair%contact%theta2, &
        phi2=pair%contact%phi2, normal_velocity_before=result%normal_velocity_before, &
        normal_velocity_after=result%normal_velocity_after, &
        psi=symmetry_axis_angle(pair%body(1)%quaternion, pair%body(2)%quaternion))
  end subroutine resolve_collision

  subroutine write_sample(output, time, pair, loads)
    type(particle_output_t), intent(inout) :: output
    real(wp), intent(in) :: time
    type(pair_t), intent(in) :: pair
    type(pair_loads_t), intent(in) :: loads
    type(particle_record_t) :: records(2)
    type(pair_record_t) :: pair_record
    integer :: i
    do i = 1, 2
      records(i) = particle_record_t(position=pair%body(i)%position, quaternion=pair%body(i)%quaternion, &
          velocity=pair%body(i)%velocity, angular_velocity=angular_velocity_lab(pair%body(i)), &
          force_hydrodynamic=loads%force_hydrodynamic(:, i), force_dlvo=loads%force_dlvo(:, i), &
          force_collision=loads%force_collision(:, i), torque_hydrodynamic=loads%torque_hydrodynamic(:, i), &
          torque_dlvo=loads%torque_dlvo(:, i), torque_collision=loads%torque_collision(:, i))
    end do
    pair_record = pair_record_t(gap=pair%contact%gap, closest_point1=pair%contact%point1, &
        closest_point2=pair%contact%point2, chi_eta=loads%chi_eta, relative_velocity=normal_approach_speed(pair), &
        vdw_force=abs(loads%vdw_force))
    call append_pair_sample(output, time, records, pair_record)
  end subroutine write_sample

  !> Normal approach speed of the closest points, > 0 approaching.
  real(wp) function normal_approach_speed(pair)
    type(pair_t), intent(in) :: pair
    normal_approach_speed = approach_speed(pair%body(1), pair%body(2), pair%contact%point1, pair%contact%point2, &
                                           pair%contact%normal)
  end function normal_approach_speed

  !> The progress line (core progress_meter) with the pair's gap and normal approach speed.
  subroutine progress_line(step, time, dt, end_time, pair, elapsed)
    integer(i8), intent(in) :: step
    real(wp), intent(in) :: time, dt, end_time, elapsed
    type(pair_t), intent(in) :: pair
    type(progress_meter_t), save :: meter
    call log_line(progress_report(meter, wall_time(), step, time, dt, elapsed / real(step, wp), end_time - time, &
                                  detail='  gap = '//scientific_text(pair%contact%gap)//' m  v_n = '// &
                                  scientific_text(normal_approach_speed(pair))//' m/s'))
  end subroutine progress_line

  !> The outcome (docs/theory.md, "Run outcome"): agglomerated when the pair has touched (at least
  !> one collision) and is bound in the DLVO well at the end — the kinetic energy of the normal
  !> relative motion of the closest points (with the reduced mass) is below the energy needed to
  !> escape from the current gap at the current chi_eta; otherwise rebounded if it collided,
  !> no_contact if it never did (a pair slowed to rest micrometres apart by Stokes drag is not an
  !> agglomerate, even though it has no kinetic energy left).
  subroutine finish_summary(cfg, models, pair, loads, time, step, max_vdw_force, wall, summary)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_models_t), intent(in) :: models
    type(pair_t), intent(in) :: pair
    type(pair_loads_t), intent(in) :: loads
    real(wp), intent(in) :: time, max_vdw_force, wall
    integer(i8), intent(in) :: step
    type(run_summary_t), intent(inout) :: summary
    logical :: bound
    bound = .false.
    if (models%dlvo .and. summary%collisions > 0) bound = relative_normal_energy(pair%body(1), pair%body(2), pair%contact) &
                             < escape_energy(models%dlvo_model, pair%contact%gap, loads%chi_eta)
    if (bound) then
      summary%outcome = 'agglomerated'
    else if (summary%collisions > 0) then
      summary%outcome = 'rebounded'
    else
      summary%outcome = 'no_contact'
    end if
    summary%name = cfg%run%name
    summary%seed = int(cfg%run%seed, i8)
    summary%shape = cfg%pair%shape
    summary%aspect_ratio = pair%shape%aspect_ratio
    summary%fluid = cfg%scene%fluid
    summary%max_vdw_force = max_vdw_force
    summary%final_gap = pair%contact%gap
    summary%final_relative_velocity = normal_approach_speed(pair)
    summary%psi_final = symmetry_axis_angle(pair%body(1)%quaternion, pair%body(2)%quaternion)
    summary%end_time = time
    summary%steps = step
    summary%wall_time = wall
  end subroutine finish_summary

  subroutine log_pair(cfg, pair)
    type(agglo_config_t), intent(in) :: cfg
    type(pair_t), intent(in) :: pair
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
  end subroutine log_pair

end module pair_scene
