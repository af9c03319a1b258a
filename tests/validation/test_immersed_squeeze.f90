!> The squeeze film resolved by the immersed boundary (ibm notes section 8.5, rung 11; issue 11,
!> validation item 5; docs/validation.md, "Lubrication"), the fast subset: two spheres of D/dx = 8 in a
!> 48 x 24 x 24 box approaching each other at fixed speed, the gap held at 2 cells (h = a/2), steady
!> Stokes flow (src/driver/squeeze_case.f90). The resolved force within 30% of Brenner's exact force
!> of the pair in unbounded fluid (Brenner 1961; measured +14%, most of it the periodic images of a
!> box only 3 D wide; a force wrong by a factor of 2 fails). The reference itself: Brenner's series
!> against its near-contact expansion is checked in tests/unit/test_lubrication.
program test_immersed_squeeze
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use squeeze_case, only: squeeze_case_t, squeeze_result_t, run_squeeze
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  type(squeeze_case_t) :: case
  type(squeeze_result_t) :: result

  call parallel_start()
  call test_start('immersed_squeeze')
  case%diameter_cells = 8.0_wp
  case%width_cells = 24
  case%gap_cells = 2.0_wp
  call run_squeeze(case, result)
  call check(result%steady, 'steady_state_reached')
  call check_below(result%reynolds, 1.0e-4_wp, 'stokes_regime')
  call check_close(result%gap_over_radius, 0.5_wp, 1.0e-12_wp, 'gap_is_half_a_radius')
  call check_close(result%force, result%reference, 0.3_wp, 'resolved_squeeze_force_vs_brenner')
  call test_finish()
end program test_immersed_squeeze
