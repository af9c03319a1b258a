!> Unit tests of the progress line: numbers keep their exponent and leading zero, and the ETA
!> follows the recent rate after dt changes. Reference values: the line's layout (docs/outputs.md,
!> run log) and a synthetic run with known wall seconds per step, for which the true time left is
!> (simulated time left / dt) x (seconds per step).
! checks: 21
program test_progress_meter
  use agglo_kinds, only: wp, i8
  use progress_meter, only: progress_meter_t, progress_report, progress_eta, scientific_text, fixed_text
  use test_framework, only: test_start, test_finish, check, check_close, check_above
  implicit none
  type(progress_meter_t) :: meter
  character(len=:), allocatable :: line
  real(wp), parameter :: end_time = 1.0e-2_wp, per_step = 1.0e-3_wp
  real(wp) :: wall, time, dt, true_eta, average_eta, eta_after_one
  integer(i8) :: step
  integer :: report

  call test_start('progress_meter')
  call check(scientific_text(2.3474e-295_wp) == '2.3474E-295', 'exponent_kept_below_1e-99', scientific_text(2.3474e-295_wp))
  call check(scientific_text(1.2598e-2_wp) == '1.2598E-002', 'three_digit_exponent', scientific_text(1.2598e-2_wp))
  call check(scientific_text(-3.0e150_wp) == '-3.0000E+150', 'negative_large', scientific_text(-3.0e150_wp))
  call check(fixed_text(0.46_wp, 2) == '0.46', 'leading_zero', fixed_text(0.46_wp, 2))
  call check(fixed_text(-0.05_wp, 2) == '-0.05', 'leading_zero_negative', fixed_text(-0.05_wp, 2))
  call check(fixed_text(12.34_wp, 1) == '12.3', 'fixed_above_one', fixed_text(12.34_wp, 1))
  call check(fixed_text(2.0e300_wp, 2) == '2.0000E+300', 'fixed_huge_as_scientific', fixed_text(2.0e300_wp, 2))
  call check(fixed_text(195.4_wp, 0) == '195' .and. fixed_text(0.2_wp, 0) == '0', 'no_decimals_no_point', &
             fixed_text(195.4_wp, 0)//' '//fixed_text(0.2_wp, 0))

  ! First report: the caller's seconds per step (0.46 ms) sets the rate; 1000 steps of dt left.
  line = progress_report(meter, 10.0_wp, 400_i8, 1.2598e-2_wp, 8.2968e-5_wp, 0.46e-3_wp, 1000 * 8.2968e-5_wp)
  call check(line == 'step 400  t = 1.2598E-002 s  dt = 8.2968E-005 s  0.460 ms/step  ETA 0.5s', 'line_layout', line)
  line = progress_report(meter, 10.5_wp, 500_i8, 2.0e-2_wp, 1.0e-4_wp, 0.0_wp, 0.0_wp, detail='  gap = 1.0E-009 m')
  call check(index(line, 'dt = 1.0000E-004 s  gap = 1.0E-009 m  5.00 ms/step  ETA 0.0s') > 0, 'detail_after_dt', line)

  line = progress_report(meter, 10.6_wp, 50500_i8, 2.1e-2_wp, 1.0e-4_wp, 0.0_wp, 0.0_wp)
  call check(index(line, '  2.00 us/step  ETA') > 0, 'microseconds_below_0.01_ms', line)

  ! Synthetic run at 1 ms per step: 100 steps of dt = 1e-6 s, then dt = 1e-5 s, a report every 10 steps.
  meter = progress_meter_t()
  wall = 0.0_wp; time = 0.0_wp; dt = 1.0e-6_wp; step = 0
  do report = 1, 30
    if (report == 11) dt = 1.0e-5_wp
    step = step + 10
    time = time + 10 * dt
    wall = wall + 10 * per_step
    line = progress_report(meter, wall, step, time, dt, per_step, end_time - time)
    if (report == 11) eta_after_one = progress_eta(meter, end_time - time)
    if (report == 20) exit
  end do
  true_eta = (end_time - time) / dt * per_step
  average_eta = (end_time - time) * wall / time     ! the rate averaged since the start
  call check_close(progress_eta(meter, end_time - time), true_eta, 0.01_wp, 'eta_follows_dt_change_in_10_reports')
  call check_above(average_eta, 1.5_wp * true_eta, 'average_since_start_would_be_far_off')
  call check_above(eta_after_one, 0.0_wp, 'eta_known_after_change')
  call check(eta_after_one < (end_time - 110 * 1.0e-6_wp) / 1.0e-6_wp * per_step, 'eta_moves_at_first_report_after_change')
  ! A step limit sooner than the end time: steps left x seconds per step.
  call check_close(progress_eta(meter, end_time - time, steps_left=5.0_wp), 5 * per_step, 1.0e-12_wp, 'step_limit_sooner')
  ! A new run in the same process (step not after the previous report) starts afresh.
  line = progress_report(meter, 100.0_wp, 10_i8, 1.0e-5_wp, 1.0e-6_wp, 2.0e-3_wp, 1.0e-6_wp)
  call check_close(progress_eta(meter, 1.0e-6_wp), 2.0e-3_wp, 1.0e-12_wp, 'new_run_restarts_meter')
  ! An estimate of 1000 days or more is shown as such, not as a duration: 1e297 steps of dt = 1e-300 s
  ! at 1 ms each, and 1000 days plus one second.
  meter = progress_meter_t()
  line = progress_report(meter, 1.0_wp, 10_i8, 1.0e-299_wp, 1.0e-300_wp, per_step, 1.0e-3_wp)
  call check(index(line, 'ETA > 1000 days') > 0 .and. index(line, 'h') == 0, 'eta_beyond_1000_days_capped', line)
  meter = progress_meter_t()
  line = progress_report(meter, 1.0_wp, 10_i8, 0.0_wp, 1.0_wp, 1.0_wp, 86400001.0_wp)
  call check(index(line, 'ETA > 1000 days') > 0, 'eta_just_beyond_1000_days_capped', line)
  meter = progress_meter_t()
  line = progress_report(meter, 1.0_wp, 10_i8, 0.0_wp, 1.0_wp, 1.0_wp, 86399000.0_wp)
  call check(index(line, 'ETA 23999h43m20s') > 0, 'eta_below_1000_days_shown', line)
  ! Before any measurement (no seconds per step from the caller) the ETA is not guessed.
  meter = progress_meter_t()
  line = progress_report(meter, 1.0_wp, 10_i8, 0.0_wp, 1.0_wp, -1.0_wp, 1.0_wp)
  call check(index(line, 'ETA unknown') > 0, 'eta_unknown_before_measurement', line)
  call test_finish()
end program test_progress_meter
