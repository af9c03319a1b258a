! checks: 3
!> The immersed-geometry classification that keeps its work arrays and node lists between calls
!> (every step of a moving body) equals a classification into a fresh geometry, on 1 rank, over 40
!> random placements of a needle and a disk (tests/unit/reclassification_check.f90): every count,
!> status, node list, stencil index and flag equal, every real field of every ghost record within
!> 1e-14 cells (the same arithmetic on the same numbers: the results do not depend on the reuse).
program test_immersed_reclassify
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed
  use fluid_grid, only: fluid_grid_t, grid_create
  use reclassification_check, only: reclassification_result_t, compare_reclassifications
  use test_framework, only: test_start, test_finish, check_equal, check_below, check_above
  implicit none
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(reclassification_result_t) :: result

  call parallel_start()
  call test_start('immersed_reclassify')
  call stream_seed(stream, 31_i8, stream_id=3)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  call compare_reclassifications(grid, stream, 40, result)
  write(*, '(a,i0,a,i0,a,i0,a,es10.3)') 'placements ', result%placements, ', ghost records ', result%ghosts, &
      ', with fallback ', result%fallbacks, ', worst real difference (cells) ', result%worst_real
  call check_equal(result%integer_mismatches, 0, 'reused_equals_fresh_nodes_and_stencils')
  call check_below(result%worst_real, 1.0e-14_wp, 'reused_equals_fresh_records')
  call check_above(real(result%fallbacks, wp), 1.0_wp, 'placements_include_fallbacks')
  call test_finish()
end program test_immersed_reclassify
