!> The narrow-band classification of immersed_geometry equals the full one on 1 rank: the same node
!> status per component, the same ghost and interior lists and the same ghost records (surface
!> point, normal, image point, stencil) on random placements of a needle, a disk and a sphere
!> (tests/unit/band_comparison.f90).
! checks: 5
program test_immersed_band
  use parallel_env, only: parallel_start
  use band_comparison, only: compare_band_with_full
  use test_framework, only: test_start, test_finish
  implicit none
  call parallel_start()
  call test_start('immersed_band')
  call compare_band_with_full(32)
  call test_finish()
end program test_immersed_band
