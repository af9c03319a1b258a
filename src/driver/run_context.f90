!> What the scene loop (module scene_loop) keeps about the run itself, beside the physics: the
!> fluid's time series and progress meter (fluid_monitor_t), the fluid-free scenes' progress meter,
!> the stage timers and the wall clocks. One value, owned by the loop, passed where it is needed.
!> The process-wide services stay modules with state (docs/design.md, "Run context"): the log
!> (core/logger: every room and the one fatal path write to it), the timer registry
!> (core/timer_registry: every room adds its own timers by name) and the run directory
!> (io/run_directory: every output file is named through it).
module run_context
  use agglo_kinds, only: wp, i8
  use progress_meter, only: progress_meter_t
  use timer_registry, only: timer_register
  use fluid_monitor, only: fluid_monitor_t
  implicit none
  private
  public :: run_context_t, run_context_start

  !> The handles of the loop's stage timers (0: the stage does not run in this scene).
  type :: stage_timers_t
    integer :: fluid_step = 0, stop_checks = 0, fluid_outputs = 0, particles = 0, fields = 0, checkpoint = 0
  end type stage_timers_t

  type :: run_context_t
    type(fluid_monitor_t) :: monitor            !< fluid_statistics.dat and the fluid's progress meter
    type(progress_meter_t) :: meter             !< the fluid-free scenes' progress meter
    type(stage_timers_t) :: timers
    real(wp) :: wall_start = 0                  !< s, wall clock at the first step of this run segment
    real(wp) :: step_wall = 0                   !< s, wall clock at the last progress line
    integer(i8) :: first_step = 0               !< the loop's step at the start (or the restart)
  end type run_context_t

contains

  !> The stage timers of a scene with or without a resolved fluid and free particles, registered
  !> in the order the breakdown lists them (every rank the same).
  subroutine run_context_start(context, with_fluid, with_particles)
    type(run_context_t), intent(out) :: context
    logical, intent(in) :: with_fluid, with_particles
    if (with_fluid) then
      context%timers%fluid_step = timer_register('fluid step')
      context%timers%stop_checks = timer_register('stop checks')
      context%timers%fluid_outputs = timer_register('fluid outputs')
      context%timers%fields = timer_register('I/O')
    end if
    if (with_particles) context%timers%particles = timer_register(trim(merge('particle sub-steps', &
                                                                              'particle step     ', with_fluid)))
    context%timers%checkpoint = timer_register('checkpoint')
  end subroutine run_context_start
end module run_context
