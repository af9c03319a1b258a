! checks: 8
!> Two equal bodies pushed together by constant equal and opposite forces in fluid at rest at the
!> 'stokes' rung, with the sub-grid lubrication at the 'stokes' scene's default hand-over
!> (docs/studies/validation.md, "Free approach under a constant force"; module push_pair_case).
!> Spheres from 2 radii apart to 10 nm, r = 50 um, against the quasi-steady approach under the exact
!> two-sphere resistance (Brenner 1961; Jeffrey & Onishi 1984 near contact):
!>  - the time to 1e-3 r within 30% (measured -24%: isolated drags plus the near-contact squeeze
!>    miss the far-field interaction, lambda - 1 = 0.60 at 2 radii, 1.04 at 1 radius; with a
!>    hand-over of half a cell of a D/dx = 8 grid, 0.125 r, the time is 44% short and this fails);
!>  - the time at every gap from 2 r to 1e-3 r within 50% (largest |t(h)/t_ref(h) - 1|, measured 44%,
!>    early in the approach, where the exact lambda is 1.6 and the isolated drags give 1);
!>  - the time from 1e-2 r to 10 nm within 3% (near contact the model is the exact expansion less
!>    its constant: measured about 1-2%).
!> Needles tip to tip and disks face to face (aspect 5): the time from 1e-2 r to 10 nm within 10% of
!> the curvature-scaled near-contact asymptote (axial drag plus 6 pi mu R_eff^2 / h).
program test_stokes_push_pair
  use agglo_kinds, only: wp
  use config_collision, only: default_lubrication_handover
  use push_pair_case, only: push_case_t, push_history_t, run_stokes_push, quasi_steady_times, history_time_error, &
                            history_time_at, tip_asymptote_time
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none
  type(push_case_t) :: case
  type(push_history_t) :: history
  real(wp), allocatable :: gaps(:), times(:)
  real(wp) :: spacing
  integer :: k

  call test_start('stokes_push_pair')
  ! The 'stokes' scene's hand-over in radii, on a grid of D/dx = 8.
  spacing = case%radius / 4.0_wp
  case%handover = default_lubrication_handover('stokes', 'resolved', 'non_incremental', case%radius, spacing) &
                  * spacing / case%radius
  call run_stokes_push(case, history)
  call check(history%reached, 'spheres_close_to_5_nm')
  gaps = [(case%radius * 10.0_wp**(log10(case%start_gap) - 0.05_wp * k), k = 1, 66)]   ! 2 r .. 1e-3 r
  times = quasi_steady_times(history%push, case%radius, case%viscosity, case%start_gap * case%radius, gaps)
  call check_close(history_time_at(history%time, history%gap, gaps(66)), times(66), 0.3_wp, 'time_to_1e-3_radius')
  call check_close(1.0_wp + history_time_error(history%time, history%gap, times, gaps), 1.0_wp, 0.5_wp, &
                   'time_at_every_gap_2_to_1e-3_radius')
  times = quasi_steady_times(history%push, case%radius, case%viscosity, case%start_gap * case%radius, &
                             [1.0e-2_wp * case%radius, 1.0e-8_wp])
  call check_close(history_time_at(history%time, history%gap, 1.0e-8_wp) &
                   - history_time_at(history%time, history%gap, 1.0e-2_wp * case%radius), times(2) - times(1), 0.03_wp, &
                   'time_from_1e-2_radius_to_10_nm')
  call tips('needle')
  call tips('disk')
  call test_finish()

contains

  !> Needles or disks along their axes: reached, and the near-contact time against the asymptote.
  subroutine tips(shape)
    character(len=*), intent(in) :: shape
    case%shape = shape
    call run_stokes_push(case, history)
    call check(history%reached, trim(shape)//'s_close_to_5_nm')
    call check_close(history_time_at(history%time, history%gap, 1.0e-8_wp) &
                     - history_time_at(history%time, history%gap, 1.0e-2_wp * case%radius), &
                     tip_asymptote_time(history, case%viscosity, 1.0e-2_wp * case%radius, 1.0e-8_wp), 0.1_wp, &
                     trim(shape)//'s_time_from_1e-2_radius_to_10_nm_vs_asymptote')
  end subroutine tips
end program test_stokes_push_pair
