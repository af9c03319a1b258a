! ranks: 2
! checks: 4
!> The immersed-geometry classification that keeps its work arrays and node lists between calls
!> equals a classification into a fresh geometry on 2 ranks (z slabs of 16 planes: bodies across
!> the rank boundary and the periodic wrap), over 40 random placements of a needle and a disk
!> (tests/unit/reclassification_check.f90), on every rank.
program test_immersed_reclassify_ranks
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, n_ranks, global_max, global_sum
  use random_stream, only: random_stream_t, stream_seed
  use fluid_grid, only: fluid_grid_t, grid_create
  use reclassification_check, only: reclassification_result_t, compare_reclassifications
  use test_framework, only: test_start, test_finish, check_equal, check_below, check_above
  implicit none
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(reclassification_result_t) :: result
  real(wp) :: mismatches, fallbacks

  call parallel_start()
  call test_start('immersed_reclassify_ranks')
  ! The same stream on every rank: every rank places the same bodies.
  call stream_seed(stream, 31_i8, stream_id=4)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  call check_equal(grid%nz_local, 32 / n_ranks, 'slab_planes')
  call compare_reclassifications(grid, stream, 40, result)
  mismatches = global_sum(real(result%integer_mismatches, wp))
  fallbacks = global_sum(real(result%fallbacks, wp))
  call check_below(mismatches, 0.5_wp, 'reused_equals_fresh_nodes_and_stencils_every_rank')
  call check_below(global_max(result%worst_real), 1.0e-14_wp, 'reused_equals_fresh_records_every_rank')
  call check_above(fallbacks, 1.0_wp, 'placements_include_fallbacks')
  call test_finish()
end program test_immersed_reclassify_ranks
