! ranks: 2
! checks: 19
!> Tests of the timer registry on 2 ranks with known durations (no sleeps, no timed assertions):
!> a replaceable clock returns readings the test sets, and timer_add takes explicit values. Rank r
!> (0 or 1) records per timer a duration that depends on r, so min / mean / max over the ranks are
!> known exactly: with d_r the seconds of rank r, min = d_0, max = d_1, mean = (d_0 + d_1) / 2.
program test_timer_registry
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, my_rank
  use timer_registry, only: timer_register, timer_tic, timer_toc, timer_add, timer_seconds, timer_count, &
                            timer_name, timer_reset_all, timer_set_clock, timer_reduce, timer_breakdown
  use test_framework, only: test_start, test_finish, check, check_close, check_equal
  implicit none
  real(wp) :: now = 0          ! the reading of the test clock, s
  integer :: alpha, beta, unused, repeat
  real(wp), allocatable :: smallest(:), mean(:), largest(:)
  character(len=80), allocatable :: lines(:)
  real(wp) :: rank_factor

  call parallel_start()
  call test_start('timer_registry')
  rank_factor = real(my_rank + 1, wp)      ! 1 on rank 0, 2 on rank 1

  alpha = timer_register('alpha')
  beta = timer_register('beta')
  unused = timer_register('never started')
  call check_equal(timer_register('alpha'), alpha, 'register_same_name_same_handle')
  call check_equal(timer_count(), 3, 'three_timers_registered')
  call check(timer_name(beta) == 'beta', 'name_of_handle')

  ! alpha: two tic/toc pairs of 0.5 s (rank 0) or 1 s (rank 1) on the test clock.
  call timer_set_clock(test_clock)
  do repeat = 1, 2
    now = 100.0_wp * repeat
    call timer_tic(alpha)
    now = now + 0.5_wp * rank_factor
    call timer_toc(alpha)
  end do
  ! beta: explicit durations 0.25 s (rank 0) and 1 s (rank 1).
  call timer_add(beta, 0.25_wp * rank_factor**2)
  call check_close(timer_seconds(alpha), rank_factor, 1.0e-15_wp, 'tic_toc_accumulates_clock_differences')

  ! Per step over 2 steps: alpha min 0.5, mean 0.75, max 1; beta min 0.125, mean 0.3125, max 0.5.
  call timer_reduce(2.0_wp, smallest, mean, largest)
  call check_close(smallest(alpha), 0.5_wp, 1.0e-15_wp, 'alpha_min_over_ranks')
  call check_close(mean(alpha), 0.75_wp, 1.0e-15_wp, 'alpha_mean_over_ranks')
  call check_close(largest(alpha), 1.0_wp, 1.0e-15_wp, 'alpha_max_over_ranks')
  call check_close(smallest(beta), 0.125_wp, 1.0e-15_wp, 'beta_min_over_ranks')
  call check_close(mean(beta), 0.3125_wp, 1.0e-15_wp, 'beta_mean_over_ranks')
  call check_close(largest(beta), 0.5_wp, 1.0e-15_wp, 'beta_max_over_ranks')
  call check_close(largest(unused), 0.0_wp, 0.0_wp, 'unstarted_timer_zero')

  ! The breakdown in ms per step: a heading, the two timers that ran, the whole step (3 s and
  ! 5 s in 2 steps: min 1500, mean 2000, max 2500 ms).
  lines = timer_breakdown(2_i8, 1.0_wp + 2.0_wp * rank_factor)
  call check_equal(size(lines), 4, 'breakdown_lists_timers_that_ran')
  call check(index(lines(2), 'alpha') > 0 .and. index(lines(2), '500.000') > 0 .and. &
             index(lines(2), '750.000') > 0 .and. index(lines(2), '1000.000') > 0, 'breakdown_alpha_row', lines(2))
  call check(index(lines(3), 'beta') > 0 .and. index(lines(3), '125.000') > 0 .and. &
             index(lines(3), '312.500') > 0 .and. index(lines(3), '500.000') > 0, 'breakdown_beta_row', lines(3))
  call check(index(lines(4), 'whole step') > 0 .and. index(lines(4), '1500.000') > 0 .and. &
             index(lines(4), '2000.000') > 0 .and. index(lines(4), '2500.000') > 0, 'breakdown_whole_step_row', lines(4))

  ! By name: a new name registers on first use (the one-line way for a new part of the code).
  now = 0
  call timer_tic('particle step')
  now = 0.125_wp
  call timer_toc('particle step')
  call check_equal(timer_count(), 4, 'tic_by_name_registers')
  call check_close(timer_seconds(timer_register('particle step')), 0.125_wp, 1.0e-15_wp, 'tic_toc_by_name')

  call timer_reset_all()
  call check_close(timer_seconds(alpha) + timer_seconds(beta), 0.0_wp, 0.0_wp, 'reset_zeroes_timers')
  call check_equal(timer_count(), 4, 'reset_keeps_registrations')
  call timer_set_clock()
  call test_finish()

contains

  function test_clock() result(seconds)
    real(wp) :: seconds
    seconds = now
  end function test_clock
end program test_timer_registry
