! checks: 4
!> The Aitken stop of sphere_array_case (used by the spheroid rungs of `make validate`): a
!> simple-cubic sphere array at phi = 0.064, D/dx = 7.9 (16^3), implicit, run once to steady state
!> (relative change of U per step below 1e-10) and once stopped by Aitken's delta-squared on U
!> sampled every 500 steps (successive estimates within 1e-6). The two drag coefficients must agree
!> to 1e-4 relative, and the Aitken run must stop in fewer steps.
program test_immersed_aitken
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none
  type(sphere_array_case_t) :: case
  type(sphere_array_result_t) :: steady, aitken

  call parallel_start()
  call test_start('immersed_aitken')
  case%cells = 16
  case%volume_fraction = 0.064_wp
  case%steady_tolerance = 1.0e-10_wp
  case%max_steps = 40000
  call run_sphere_array(case, steady)
  case%aitken_window = 500
  call run_sphere_array(case, aitken)
  print '(a,f9.6,a,i0,a,f9.6,a,i0,a)', 'K steady ', steady%drag_coefficient, ' (', steady%steps, ' steps), Aitken ', &
      aitken%drag_coefficient, ' (', aitken%steps, ' steps)'
  call check(steady%steady .and. .not. steady%extrapolated, 'reference_run_steady')
  call check(aitken%extrapolated, 'aitken_run_stopped_by_estimate')
  call check(aitken%steps < steady%steps, 'aitken_run_shorter')
  call check_close(aitken%drag_coefficient, steady%drag_coefficient, 1.0e-4_wp, 'aitken_drag_equals_steady_1e-4')
  call test_finish()
end program test_immersed_aitken
