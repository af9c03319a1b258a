! checks: 6
!> Node counts of the immersed-boundary classification under sub-cell shifts (the validation ladder,
!> rung 1; docs/studies/validation.md): a needle and a disk of aspect 5 (volume-equivalent radius 0.1 mm
!> in a 1 mm box at 64^3: 4.4 and 7.5 cells thin), each at three fixed random orientations, moved by
!> 16 random sub-cell shifts. Per orientation and component, the spread (largest minus smallest) of
!> the ghost count and of the interior count, in surface layers of S/dx^2 nodes (S the spheroid's
!> surface area): a shift moves the surface by less than a cell, so a count can change by at most
!> about one layer; lattice-point counts of a smooth surface fluctuate far less, like the square
!> root of the layer (sqrt(700) = 26 nodes, 0.04 layer), and the bound is 0.2 layer (the sphere
!> case, D/dx 8-16, is in test_immersed_geometry).
program test_immersed_shifts
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid, surface_area
  use fluid_grid, only: fluid_grid_t, grid_create
  use immersed_geometry, only: immersed_body_t, immersed_options_t, immersed_geometry_t, classify_nodes
  use test_framework, only: test_start, test_finish, check, check_below
  implicit none
  character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
  integer, parameter :: n_cells = 64, n_orientations = 3, n_shifts = 16
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_body_t) :: body(1)
  type(immersed_options_t) :: options
  type(immersed_geometry_t) :: geometry
  integer :: s, o, t, c, ghost_min(3), ghost_max(3), interior_min(3), interior_max(3)
  real(wp) :: layer, spread_ghost, spread_interior

  call parallel_start()
  call test_start('immersed_shifts')
  call stream_seed(stream, 77_i8, stream_id=9)
  call grid_create(grid, n_cells, n_cells, n_cells, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  do s = 1, size(shapes)
    body(1)%shape = make_spheroid(trim(shapes(s)), 0.1e-3_wp, 1000.0_wp)
    layer = surface_area(body(1)%shape) / grid%dx**2
    spread_ghost = 0
    spread_interior = 0
    do o = 1, n_orientations
      body(1)%orientation = random_orientation(stream)
      ghost_min = huge(1); ghost_max = 0; interior_min = huge(1); interior_max = 0
      do t = 1, n_shifts
        body(1)%centre = (0.5_wp * n_cells + [stream_uniform(stream), stream_uniform(stream), &
                                              stream_uniform(stream)]) * grid%dx
        call classify_nodes(grid, body, options, geometry)
        do c = 1, 3
          ghost_min(c) = min(ghost_min(c), geometry%component(c)%n_ghost)
          ghost_max(c) = max(ghost_max(c), geometry%component(c)%n_ghost)
          interior_min(c) = min(interior_min(c), geometry%component(c)%n_interior)
          interior_max(c) = max(interior_max(c), geometry%component(c)%n_interior)
        end do
      end do
      spread_ghost = max(spread_ghost, maxval(ghost_max - ghost_min) / layer)
      spread_interior = max(spread_interior, maxval(interior_max - interior_min) / layer)
      print '(a,a,i0,a,3(i6,a,i6,2x),a,3(i6,a,i6,2x),a,f8.0)', trim(shapes(s)), ' orientation ', o, &
          ': ghosts (u, v, w) ', (ghost_min(c), '-', ghost_max(c), c = 1, 3), 'interior ', &
          (interior_min(c), '-', interior_max(c), c = 1, 3), 'layer ', layer
    end do
    print '(a,a,2f8.4)', trim(shapes(s)), ': spread under shifts, in surface layers (ghost, interior): ', &
        spread_ghost, spread_interior
    call check(minval(ghost_min) > 0, trim(shapes(s))//'_has_ghost_nodes')
    call check_below(spread_ghost, 0.2_wp, trim(shapes(s))//'_ghost_count_spread_below_0.2_layer')
    call check_below(spread_interior, 0.2_wp, trim(shapes(s))//'_interior_count_spread_below_0.2_layer')
  end do
  call test_finish()
end program test_immersed_shifts
