!> Benchmark of one particle step of a pair (`make bench`): closest points (warm start), DLVO at
!> the closest points, collision test, Stokes loads and the rigid-body update of both bodies, each
!> timed separately over many steps of the paper's quiescent disk pair (medians of repeats).
!> Usage: bench_pair [steps]. Prints one line per part in ns per step.
program bench_pair
  use agglo_kinds, only: wp
  use wall_clock, only: wall_time
  use config_pair, only: pair_config_t
  use config_dlvo, only: dlvo_config_t
  use config_collision, only: collision_config_t
  use pair_setup, only: pair_t, build_pair
  use closest_points, only: closest_points_t, find_closest_points
  use dlvo, only: dlvo_model_t, dlvo_setup, dlvo_evaluation_t, dlvo_evaluate
  use collision, only: collision_model_t, collision_setup, collision_detected
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_of, stokes_loads
  use rigid_body, only: rigid_body_step, integrator_euler
  use parallel_env, only: parallel_start, parallel_stop
  use sample_statistics, only: median
  implicit none
  integer, parameter :: repeats = 5
  character(len=*), parameter :: parts(5) = [character(len=16) :: 'closest_points', 'dlvo', 'collision_test', &
                                             'stokes_loads', 'rigid_body_x2']
  type(pair_config_t) :: pair_cfg
  type(pair_t) :: pair, start
  type(closest_points_t) :: previous
  type(dlvo_model_t) :: dlvo_model
  type(dlvo_evaluation_t) :: evaluation
  type(collision_model_t) :: collision_model
  type(stokes_resistance_t) :: resistance
  real(wp) :: seconds(5, repeats), t0, force(3, 2), torque(3, 2), dt
  character(len=32) :: argument
  integer :: steps, repeat, step, i, part
  logical :: hit

  call parallel_start()
  steps = 100000
  if (command_argument_count() >= 1) then
    call get_command_argument(1, argument)
    read(argument, *) steps
  end if
  dt = 2.0e-7_wp
  call build_pair(pair_cfg, 1, start)
  call dlvo_setup(dlvo_model, dlvo_config_t(), pair_cfg%radius)
  call collision_setup(collision_model, collision_config_t())
  resistance = stokes_resistance_of(start%shape, 997.0_wp * 1.0e-6_wp)
  seconds = 0.0_wp
  hit = .false.
  do repeat = 1, repeats
    pair = start
    do step = 1, steps
      t0 = wall_time()
      previous = pair%contact
      call find_closest_points(pair%shape, pair%body(1)%position, pair%body(1)%quaternion, pair%shape, &
                               pair%body(2)%position, pair%body(2)%quaternion, pair%contact, previous=previous)
      call lap(1)
      call dlvo_evaluate(dlvo_model, pair%shape, pair%body(1), pair%shape, pair%body(2), pair%contact, evaluation)
      call lap(2)
      hit = hit .neqv. collision_detected(collision_model, pair%body(1), pair%body(2), pair%contact, dt)
      call lap(3)
      do i = 1, 2
        call stokes_loads(resistance, pair%body(i), force(:, i), torque(:, i))
      end do
      call lap(4)
      call rigid_body_step(pair%body(1), force(:, 1) + evaluation%force1, torque(:, 1) + evaluation%torque1, dt, &
                           integrator_euler)
      call rigid_body_step(pair%body(2), force(:, 2) + evaluation%force2, torque(:, 2) + evaluation%torque2, dt, &
                           integrator_euler)
      call lap(5)
    end do
  end do
  do part = 1, size(parts)
    write(*, '(a16,i10,a)') parts(part), nint(1.0e9_wp * median(seconds(part, :)) / steps), ' ns/step'
  end do
  write(*, '(a16,i10,a,l2)') 'whole_step', nint(1.0e9_wp * median(sum(seconds, dim=1)) / steps), ' ns/step', hit
  call parallel_stop()

contains

  !> Add the time since t0 to part `which` of this repeat and restart the clock.
  subroutine lap(which)
    integer, intent(in) :: which
    real(wp) :: now
    now = wall_time()
    seconds(which, repeat) = seconds(which, repeat) + (now - t0)
    t0 = now
  end subroutine lap
end program bench_pair
