! checks: 5
!> A free sphere pair pushed together head-on in fluid at rest, resolved by the immersed boundary
!> (docs/studies/validation.md, "Lubrication", free pair approach; module
!> squeeze_case, run_free_squeeze), the fast subset: D/dx = 8 in a 48 x 24 x 24 box, constant
!> opposite pushes F = 6 pi mu a U_p (U_p a / nu = 0.3), from rest 2 cells apart to 0.2 cell, without
!> and with the sub-grid lubrication at the deck's default hand-over for the case's incremental
!> pressure (&collision lubrication_handover, config_collision's default_lubrication_handover).
!> Reference: Brenner's (1961) exact resistance of two spheres approaching along their line of
!> centres, F_B = 6 pi mu a beta(h) U at the measured speed U.
!>  - 1.5 cells apart the resolved force is within 25% of F_B (the grid carries the squeeze; measured
!>    +16%, most of it the periodic images of a box 3 D wide, as in test_immersed_squeeze);
!>  - a quarter cell apart, without lubrication the resolved force misses the squeeze (below 0.8 F_B;
!>    measured 0.71: the grid no longer resolves the film), with lubrication the total, resolved plus
!>    sub-grid, is within 20% of F_B (measured +7% at the default hand-over of half a cell; a hand-over
!>    of 1 cell counts the squeeze the grid still carries twice, +31%, and fails).
program test_free_squeeze
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: parallel_start
  use config_collision, only: default_lubrication_handover
  use squeeze_case, only: free_squeeze_case_t, free_squeeze_history_t, run_free_squeeze, free_squeeze_sample, &
                          brenner_squeeze_coefficient, squeeze_dynamic_viscosity
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  type(free_squeeze_case_t) :: case
  type(free_squeeze_history_t) :: free, lubricated

  call parallel_start()
  call test_start('free_squeeze')
  case%width_cells = 24
  case%start_gap_cells = 2.0_wp
  case%stop_gap_cells = 0.2_wp
  case%push_reynolds = 0.3_wp
  call run_free_squeeze(case, free)
  call check(free%reached, 'free_pair_closes_to_a_fifth_of_a_cell')
  call check_close(force_at(free, free%resolved, 1.5_wp), brenner_at(free, 1.5_wp), 0.25_wp, &
                   'resolved_force_at_1.5_cells_vs_brenner')
  call check_below(force_at(free, free%resolved, 0.25_wp) / brenner_at(free, 0.25_wp), 0.8_wp, &
                   'resolved_force_at_quarter_cell_misses_the_squeeze')

  case%lubrication = .true.
  case%handover_cells = default_lubrication_handover('resolved', 'resolved', case%pressure_scheme, 1.0_wp, 1.0_wp)
  call run_free_squeeze(case, lubricated)
  call check(lubricated%reached, 'lubricated_pair_closes_to_a_fifth_of_a_cell')
  call check_close(force_at(lubricated, lubricated%resolved + lubricated%lubrication, 0.25_wp), &
                   brenner_at(lubricated, 0.25_wp), 0.2_wp, 'resolved_plus_lubrication_at_quarter_cell_vs_brenner')
  call test_finish()

contains

  real(wp) function force_at(history, force, gap_cells)
    type(free_squeeze_history_t), intent(in) :: history
    real(wp), intent(in) :: force(:), gap_cells
    force_at = free_squeeze_sample(history, force, gap_cells * history%cell)
  end function force_at

  !> Brenner's force at the speed the run had at that gap.
  real(wp) function brenner_at(history, gap_cells)
    type(free_squeeze_history_t), intent(in) :: history
    real(wp), intent(in) :: gap_cells
    brenner_at = 6.0_wp * pi * squeeze_dynamic_viscosity * history%radius &
                 * brenner_squeeze_coefficient(gap_cells * history%cell / history%radius) &
                 * free_squeeze_sample(history, history%speed, gap_cells * history%cell)
  end function brenner_at
end program test_free_squeeze
