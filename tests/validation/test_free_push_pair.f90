! checks: 3
!> The pushed sphere pair resolved by the immersed boundary, the short version of bench_push_pair's
!> resolved rung (docs/studies/validation.md, "Free approach under a constant force"): D/dx = 8 in a
!> 48 x 24 x 24 box, constant opposite pushes (U_p a / nu = 0.3), from rest a quarter radius apart
!> to 5 nm, with the sub-grid lubrication at the hand-over of the case's incremental pressure
!> (0.5 cell; config_collision, default_lubrication_handover). Reference: the quasi-steady approach
!> under the exact two-sphere resistance (Brenner 1961; Jeffrey & Onishi 1984 near contact; module
!> push_pair_case).
!>  - the time from 1e-2 r to 10 nm within 5% (the model's range: measured +1% from 2 radii at
!>    U_p a / nu = 0.1, make validate);
!>  - the time from 0.1 r to 1e-2 r within 15% (the hand-over at 0.5 cell = 0.125 r lies inside:
!>    resolved film above, model below).
program test_free_push_pair
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use config_collision, only: default_lubrication_handover
  use squeeze_case, only: free_squeeze_case_t, free_squeeze_history_t, run_free_squeeze, squeeze_dynamic_viscosity
  use push_pair_case, only: quasi_steady_times, history_time_at
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none
  type(free_squeeze_case_t) :: case
  type(free_squeeze_history_t) :: history
  real(wp) :: marks(3), times(3), measured(3)
  integer :: k

  call parallel_start()
  call test_start('free_push_pair')
  case%width_cells = 24
  case%start_gap_cells = 1.0_wp                     ! a quarter radius at D/dx = 8
  case%push_reynolds = 0.3_wp
  case%lubrication = .true.
  case%handover_cells = default_lubrication_handover('resolved', 'resolved', case%pressure_scheme, 1.0_wp, 1.0_wp)
  case%max_steps = 100000
  case%stop_gap_cells = 5.0e-9_wp / (1.0e-3_wp / (2 * case%width_cells))   ! 5 nm in cells of the 1 mm box
  call run_free_squeeze(case, history)
  call check(history%reached, 'pair_closes_to_5_nm')
  marks = [0.1_wp, 1.0e-2_wp, 0.0_wp] * history%radius
  marks(3) = 1.0e-8_wp
  times = quasi_steady_times(history%push, history%radius, squeeze_dynamic_viscosity, &
                             case%start_gap_cells * history%cell, marks)
  do k = 1, 3
    measured(k) = history_time_at(history%time, history%gap, marks(k))
  end do
  call check_close(measured(3) - measured(2), times(3) - times(2), 0.05_wp, 'time_from_1e-2_radius_to_10_nm')
  call check_close(measured(2) - measured(1), times(2) - times(1), 0.15_wp, 'time_from_0.1_to_1e-2_radius')
  call test_finish()
end program test_free_push_pair
