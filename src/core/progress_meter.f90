!> The progress line of a run and its estimate of the time left.
!>
!> "step 400  t = 1.2598E-002 s  dt = 8.2968E-005 s<detail>  0.460 ms/step  ETA 17.1s"
!>
!> Every number keeps its exponent (three digits: a time of 1e-300 s stays readable) and its leading
!> zero; the wall time per step is in ms, or in us below 0.01 ms. The ETA follows the recent rate,
!> not the average since the start: the meter keeps exponentially weighted averages of the wall
!> seconds per simulated second and per step over the intervals between reports, with half the
!> weight on the latest interval (an interval k reports old weighs 2^-(k+1)), so after a change of
!> dt the estimate settles within a few reports. The time left is (simulated time left) x (wall
!> seconds per simulated second), or the steps left to a step limit x (wall seconds per step) if
!> that is sooner. An estimate of 1000 days or more is shown as "ETA > 1000 days", none before the
!> first measurement as "ETA unknown".
module progress_meter
  use agglo_kinds, only: wp, i8
  use wall_clock, only: format_duration
  use text_format, only: int_text
  implicit none
  private
  public :: progress_meter_t, progress_report, progress_eta, scientific_text, fixed_text

  type, public :: progress_meter_t
    private
    logical :: has_previous = .false.
    real(wp) :: wall = 0.0_wp, time = 0.0_wp
    integer(i8) :: step = 0
    real(wp) :: seconds_per_step = -1.0_wp           ! < 0: not measured yet
    real(wp) :: seconds_per_simulated_second = -1.0_wp
    real(wp) :: last_seconds_per_step = -1.0_wp      ! over the latest interval only (the line shows it)
  end type progress_meter_t

  !> Weight of the latest interval in the running averages.
  real(wp), parameter :: latest_weight = 0.5_wp
  !> Beyond 1000 days an estimate says nothing a user can act on (and the duration is printed from
  !> an integer): the line shows "ETA > 1000 days" instead of a number.
  real(wp), parameter :: longest_eta = 1000 * 86400.0_wp

contains

  !> Record a report at wall-clock time wall (s) and return its line. seconds_per_step is the
  !> caller's own measure of the step rate, used only at the first report (no interval measured yet).
  !> time_left: simulated seconds to the end time; steps_left: steps to a step limit, if any; detail:
  !> text placed after dt (the scene's own quantities).
  function progress_report(meter, wall, step, time, dt, seconds_per_step, time_left, steps_left, detail) result(line)
    type(progress_meter_t), intent(inout) :: meter
    real(wp), intent(in) :: wall, time, dt, seconds_per_step, time_left
    integer(i8), intent(in) :: step
    real(wp), intent(in), optional :: steps_left
    character(len=*), intent(in), optional :: detail
    character(len=:), allocatable :: line
    real(wp) :: eta
    call record_interval(meter, wall, step, time, seconds_per_step, dt)
    eta = progress_eta(meter, time_left, steps_left)
    line = 'step '//int_text(step)//'  t = '//scientific_text(time)//' s  dt = '//scientific_text(dt)//' s'
    if (present(detail)) line = line//detail
    line = line//'  '//per_step_text(meter%last_seconds_per_step)//'  ETA '
    if (eta >= longest_eta) then
      line = line//'> 1000 days'
    else if (eta >= 0.0_wp) then
      line = line//trim(format_duration(eta))
    else
      line = line//'unknown'
    end if
  end function progress_report

  !> Wall seconds left: time_left x the recent seconds per simulated second, or steps_left x the
  !> recent seconds per step if given and sooner; < 0 before any measurement.
  pure function progress_eta(meter, time_left, steps_left) result(eta)
    type(progress_meter_t), intent(in) :: meter
    real(wp), intent(in) :: time_left
    real(wp), intent(in), optional :: steps_left
    real(wp) :: eta
    eta = -1.0_wp
    if (meter%seconds_per_simulated_second >= 0.0_wp) eta = max(time_left, 0.0_wp) * meter%seconds_per_simulated_second
    if (present(steps_left) .and. meter%seconds_per_step >= 0.0_wp) then
      if (eta < 0.0_wp) then
        eta = max(steps_left, 0.0_wp) * meter%seconds_per_step
      else
        eta = min(eta, max(steps_left, 0.0_wp) * meter%seconds_per_step)
      end if
    end if
  end function progress_eta

  !> Update the averages with the interval since the previous report. A report at a step not after
  !> the previous one (a new run in the same process) starts the meter afresh.
  subroutine record_interval(meter, wall, step, time, seconds_per_step, dt)
    type(progress_meter_t), intent(inout) :: meter
    real(wp), intent(in) :: wall, time, seconds_per_step, dt
    integer(i8), intent(in) :: step
    real(wp) :: per_step, per_simulated_second
    if (meter%has_previous .and. step <= meter%step) meter = progress_meter_t()
    if (.not. meter%has_previous) then
      meter%last_seconds_per_step = seconds_per_step
      meter%seconds_per_step = seconds_per_step
      if (dt > 0.0_wp .and. seconds_per_step >= 0.0_wp) meter%seconds_per_simulated_second = seconds_per_step / dt
    else
      per_step = max(wall - meter%wall, 0.0_wp) / real(step - meter%step, wp)
      meter%last_seconds_per_step = per_step
      meter%seconds_per_step = running_average(meter%seconds_per_step, per_step)
      if (time > meter%time) then
        per_simulated_second = max(wall - meter%wall, 0.0_wp) / (time - meter%time)
        meter%seconds_per_simulated_second = running_average(meter%seconds_per_simulated_second, per_simulated_second)
      end if
    end if
    meter%has_previous = .true.
    meter%wall = wall
    meter%time = time
    meter%step = step
  end subroutine record_interval

  pure real(wp) function running_average(average, latest)
    real(wp), intent(in) :: average, latest
    if (average < 0.0_wp) then
      running_average = latest
    else
      running_average = latest_weight * latest + (1.0_wp - latest_weight) * average
    end if
  end function running_average

  !> x as 1.2345E-003 (ES with a three-digit exponent, so 1e-300 keeps its exponent letter).
  pure function scientific_text(x) result(text)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: text
    character(len=16) :: buffer
    write(buffer, '(es12.4e3)') x
    text = trim(adjustl(buffer))
  end function scientific_text

  !> x with the given number of decimals and a leading zero (0.46, -0.05, not .46); from 1e15 on
  !> (or NaN) as scientific_text.
  pure function fixed_text(x, decimals) result(text)
    real(wp), intent(in) :: x
    integer, intent(in) :: decimals
    character(len=:), allocatable :: text
    character(len=48) :: buffer
    character(len=16) :: form
    if (.not. abs(x) < 1.0e15_wp) then               ! too long for a fixed-point field (or NaN)
      text = scientific_text(x)
      return
    else if (decimals <= 0) then
      write(buffer, '(f0.0)') anint(x)
      buffer = buffer(1:index(buffer, '.') - 1)      ! 195, not 195.
      if (len_trim(buffer) == 0 .or. trim(buffer) == '-') buffer = trim(buffer)//'0'
    else
      write(form, '(a,i0,a)') '(f0.', decimals, ')'
      write(buffer, form) x
    end if
    text = trim(adjustl(buffer))
    if (text(1:1) == '.') then
      text = '0'//text
    else if (len(text) > 1) then
      if (text(1:2) == '-.') text = '-0'//text(2:)
    end if
  end function fixed_text

  !> Wall time per step with three significant digits in ms, or in us (ns) below 0.01 ms (us):
  !> 46.0 ms/step, 0.460 ms/step, 2.04 us/step; "unknown" before any measurement.
  pure function per_step_text(seconds) result(text)
    real(wp), intent(in) :: seconds
    character(len=:), allocatable :: text
    if (seconds < 0.0_wp) then
      text = 'unknown'
    else if (seconds >= 1.0e-5_wp) then
      text = three_digits(1.0e3_wp * seconds)//' ms/step'
    else if (seconds >= 1.0e-8_wp) then
      text = three_digits(1.0e6_wp * seconds)//' us/step'
    else
      text = three_digits(1.0e9_wp * seconds)//' ns/step'
    end if
  end function per_step_text

  !> x >= 0 with three significant digits from 0.01 up (0.0123, 0.123, 1.23, 12.3, 123, 1234),
  !> smaller values with an exponent.
  pure function three_digits(x) result(text)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: text
    if (x >= 99.95_wp) then
      text = fixed_text(x, 0)
    else if (x >= 9.995_wp) then
      text = fixed_text(x, 1)
    else if (x >= 0.9995_wp) then
      text = fixed_text(x, 2)
    else if (x >= 0.09995_wp) then
      text = fixed_text(x, 3)
    else if (x >= 0.009995_wp) then
      text = fixed_text(x, 4)
    else
      text = scientific_text(x)
    end if
  end function three_digits
end module progress_meter
