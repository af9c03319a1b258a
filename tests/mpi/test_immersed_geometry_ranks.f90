! ranks: 2
! checks: 14
!> Tests of immersed_geometry on 2 ranks (z slabs of 16 planes): bodies across the rank boundary
!> (z = L/2) and across the periodic wrap (z = 0, which is also a rank boundary). Each rank's
!> classification, halo ring included, equals the brute-force reference
!> (tests/unit/immersed_reference.f90) node by node; the global counts equal the reference's
!> whole-box counts; every ghost record passes the geometric checks, its stencil flags name the
!> right status also for nodes on the other rank, and the stencils do reach the other rank.
program test_immersed_geometry_ranks
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, n_ranks, global_max, global_sum
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create
  use immersed_geometry, only: immersed_body_t, immersed_options_t, immersed_geometry_t, classify_nodes, &
                               node_ghost, node_interior
  use immersed_reference, only: record_errors_t, reference_status, check_geometry_against_reference
  use test_framework, only: test_start, test_finish, check_equal, check_below, check_above, check_close
  implicit none
  real(wp), parameter :: density = 2710.0_wp
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_options_t) :: options
  type(immersed_geometry_t) :: geometry
  type(immersed_body_t) :: bodies(2)
  type(record_errors_t) :: errors
  integer :: variant, c, i, j, k, count_mismatches, remote_corners, halo_needed
  integer :: reference_ghosts, reference_interior
  integer(int8) :: s
  real(wp) :: dx

  call parallel_start()
  call test_start('immersed_geometry_ranks')
  ! The same stream on every rank: every rank places the same bodies.
  call stream_seed(stream, 22_i8, stream_id=9)
  call grid_create(grid, 32, 32, 32, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  call check_equal(grid%nz_local, 32 / n_ranks, 'slab_planes')
  dx = grid%dx
  errors = record_errors_t()
  count_mismatches = 0
  remote_corners = 0
  halo_needed = 0
  do variant = 1, 4
    options%image_point = merge('mirror', 'image ', variant <= 2)
    ! A sphere of D/dx = 10 on the rank boundary z = L/2; a needle (aspect 5, 2a = 18.7 dx) across
    ! the periodic wrap z = 0, at random sub-cell offsets and orientations.
    bodies(1)%shape = make_spheroid('sphere', 5.0_wp * dx, density)
    bodies(1)%centre = ([0.3_wp, 0.6_wp, 0.5_wp] * grid%nx + [stream_uniform(stream), stream_uniform(stream), &
                        stream_uniform(stream)] - 0.5_wp) * dx
    bodies(1)%orientation = random_orientation(stream)
    bodies(2)%shape = make_spheroid('needle', 4.0_wp * dx, density)
    bodies(2)%centre = ([0.7_wp, 0.3_wp, 0.0_wp] * grid%nx + [stream_uniform(stream), stream_uniform(stream), &
                        stream_uniform(stream)] - 0.5_wp) * dx
    bodies(2)%orientation = random_orientation(stream)
    call classify_nodes(grid, bodies, options, geometry)
    call check_geometry_against_reference(grid, bodies, variant <= 2, geometry, errors)
    do c = 1, 3
      ! Whole-box reference counts (every rank computes them; no communication).
      reference_ghosts = 0
      reference_interior = 0
      do k = 1, grid%nz
        do j = 1, grid%ny
          do i = 1, grid%nx
            s = reference_status(grid, bodies, c, i, j, k)
            if (s == node_ghost) reference_ghosts = reference_ghosts + 1
            if (s == node_interior) reference_interior = reference_interior + 1
          end do
        end do
      end do
      if (nint(global_sum(real(geometry%component(c)%n_ghost, wp))) /= reference_ghosts) &
        count_mismatches = count_mismatches + 1
      if (nint(global_sum(real(geometry%component(c)%n_interior, wp))) /= reference_interior) &
        count_mismatches = count_mismatches + 1
      do i = 1, geometry%component(c)%n_ghost
        remote_corners = remote_corners + count(.not. geometry%component(c)%ghost(i)%stencil_local)
      end do
      halo_needed = max(halo_needed, geometry%component(c)%halo_planes_needed)
    end do
  end do

  call check_equal(nint(global_sum(real(errors%status_mismatches, wp))), 0, 'status_equals_reference_on_every_rank')
  call check_equal(nint(global_sum(real(errors%list_mismatches, wp))), 0, 'lists_and_stencil_links_consistent')
  call check_equal(count_mismatches, 0, 'global_counts_equal_whole_box_reference')
  call check_equal(nint(global_sum(real(errors%neighbour_violations, wp))), 0, &
                   'ghosts_touch_fluid_interior_and_fluid_never_meet')
  call check_below(global_max(errors%ghost_distance), 1.0e-12_wp, 'G_equals_B_minus_dG_n')
  call check_below(global_max(errors%image_distance), 1.0e-12_wp, 'M_at_dM_from_surface')
  call check_below(global_max(errors%mirror), 1.0e-12_wp, 'M_equals_2B_minus_G_for_mirror')
  call check_below(global_max(errors%weight_sum), 1.0e-14_wp, 'weights_sum_one')
  call check_below(global_max(errors%linear_field), 1.0e-12_wp, 'stencil_exact_for_linear_field')
  call check_above(-global_max(-errors%min_outside), 0.0_wp, 'M_outside_every_body')
  ! The bodies straddle both rank boundaries, so some stencils must reach the other rank, and no
  ! further than the planes the classification covers (ceil(1 + 1.5) + 1 = 4 for the image point).
  call check_above(global_sum(real(remote_corners, wp)), 1.0_wp, 'stencils_reach_the_other_rank')
  call check_above(global_max(real(halo_needed, wp)), 1.0_wp, 'halo_planes_needed_positive')
  call check_below(global_max(real(halo_needed, wp)), 4.0_wp, 'halo_planes_needed_at_most_4')
  call test_finish()
end program test_immersed_geometry_ranks
