!> What a resolved run tells its user while it runs: the fluid time series (fluid_statistics.dat),
!> the progress line, and the per-step timing breakdown at the end. The open file and the progress
!> meter are a fluid_monitor_t the scene loop's run context owns (module run_context), not module state.
module fluid_monitor
  use agglo_kinds, only: wp, i8
  use logger, only: log_line
  use parallel_env, only: is_root
  use wall_clock, only: wall_time
  use progress_meter, only: progress_meter_t, progress_report
  use text_series, only: drop_rows_after
  use fluid_diagnostics, only: fluid_statistics_t
  use timer_registry, only: timer_breakdown
  implicit none
  private
  public :: fluid_monitor_t, statistics_open, statistics_write, statistics_close, progress_line, timing_report

  !> The fluid time series being written and the progress line's meter.
  type :: fluid_monitor_t
    integer :: statistics_unit = -1            !< fluid_statistics.dat on rank 0 (-1: not open)
    type(progress_meter_t) :: meter
  end type fluid_monitor_t

contains

  !> Rank 0 opens the time series. A restarted run (append) continues it from the checkpoint of
  !> step last_step: the rows an interrupted run wrote after that step are dropped first, so every
  !> step appears once and the file equals that of an uninterrupted run.
  subroutine statistics_open(monitor, path, append, last_step)
    type(fluid_monitor_t), intent(inout) :: monitor
    character(len=*), intent(in) :: path
    logical, intent(in) :: append
    integer(i8), intent(in) :: last_step
    logical :: exists
    if (.not. is_root()) return
    inquire(file=path, exist=exists)
    if (append .and. exists) then
      call drop_rows_after(path, last_step, 6)
      open(newunit=monitor%statistics_unit, file=path, status='old', position='append', action='write')
    else
      open(newunit=monitor%statistics_unit, file=path, status='replace', action='write')
      write(monitor%statistics_unit, '(a)') '# Agglo fluid time series (volume averages per unit mass; docs/decks.md, &output)'
      write(monitor%statistics_unit, '(a)') '# step  time[s]  dt[s]  kinetic_energy[m2/s2]  dissipation[m2/s3]  '// &
                                    'max_divergence[1/s]  cfl'
    end if
  end subroutine statistics_open

  subroutine statistics_write(monitor, step, time, dt, stats)
    type(fluid_monitor_t), intent(in) :: monitor
    integer(i8), intent(in) :: step
    real(wp), intent(in) :: time, dt
    type(fluid_statistics_t), intent(in) :: stats
    if (monitor%statistics_unit == -1) return
    write(monitor%statistics_unit, '(i10,6es24.16)') step, time, dt, stats%kinetic_energy, stats%dissipation, &
        stats%max_divergence, stats%cfl
    flush(monitor%statistics_unit)
  end subroutine statistics_write

  subroutine statistics_close(monitor)
    type(fluid_monitor_t), intent(inout) :: monitor
    if (monitor%statistics_unit /= -1) close(monitor%statistics_unit)
    monitor%statistics_unit = -1
  end subroutine statistics_close

  !> "step 120  t = 1.2000E-003 s  dt = 1.0000E-005 s  3.21 ms/step  ETA 12.0s" (core progress_meter:
  !> the ETA follows the recent rate of simulated time; steps_left x dt is the simulated time left).
  subroutine progress_line(monitor, step, time, dt, seconds_per_step, steps_left)
    type(fluid_monitor_t), intent(inout) :: monitor
    integer(i8), intent(in) :: step
    real(wp), intent(in) :: time, dt, seconds_per_step, steps_left
    call log_line(progress_report(monitor%meter, wall_time(), step, time, dt, seconds_per_step, steps_left * dt, steps_left))
  end subroutine progress_line

  !> Milliseconds per step of every registered timer and of the whole step: min / mean / max over
  !> the ranks (collective).
  subroutine timing_report(steps, total_seconds)
    integer(i8), intent(in) :: steps
    real(wp), intent(in) :: total_seconds
    character(len=80), allocatable :: lines(:)
    integer :: n
    if (steps <= 0) return
    lines = timer_breakdown(steps, total_seconds)
    do n = 1, size(lines)
      call log_line(trim(lines(n)))
    end do
  end subroutine timing_report
end module fluid_monitor
