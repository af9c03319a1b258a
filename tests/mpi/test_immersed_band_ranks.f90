! ranks: 2
!> The narrow-band classification of immersed_geometry equals the full one on 2 ranks (z slabs of
!> 16 planes, bodies across the rank boundaries and the periodic wrap): the same node status per
!> component, lists and ghost records on every rank (tests/unit/band_comparison.f90).
! checks: 5
program test_immersed_band_ranks
  use parallel_env, only: parallel_start
  use band_comparison, only: compare_band_with_full
  use test_framework, only: test_start, test_finish
  implicit none
  call parallel_start()
  call test_start('immersed_band_ranks')
  call compare_band_with_full(32)
  call test_finish()
end program test_immersed_band_ranks
