! checks: 57
!> Tests of immersed_geometry on 1 rank: node classification of u, v, w against an independent
!> brute-force reference (tests/unit/immersed_reference.f90) for spheres of D/dx = 8 to 16 at random
!> sub-cell offsets, needles and disks at random orientations, a body straddling the periodic wrap,
!> two bodies in near contact; count bounds that follow from the geometry; the ghost records
!> (closest point, mirror and image points, trilinear stencil); the thin-dimension cell count.
program test_immersed_geometry
  use agglo_kinds, only: wp, i8
  use physical_constants, only: pi
  use parallel_env, only: parallel_start
  use random_stream, only: random_stream_t, stream_seed, stream_uniform, stream_normal
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create
  use immersed_geometry, only: immersed_body_t, immersed_options_t, immersed_geometry_t, classify_nodes, &
                               thin_dimension_cells, node_position
  use periodic_box, only: minimum_image
  use immersed_reference, only: record_errors_t, check_geometry_against_reference
  use wall_clock, only: wall_time
  use test_framework, only: test_start, test_finish, check, check_close, check_below, check_above, check_equal
  implicit none
  real(wp), parameter :: density = 2710.0_wp, paper_radius = 50.0e-6_wp
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  type(immersed_options_t) :: mirror_options, image_options
  type(immersed_geometry_t) :: geometry, shifted
  type(immersed_body_t) :: bodies(2), one(1)
  type(record_errors_t) :: errors, image_errors
  real(wp) :: dx, diameter, r_cells, solid_low, solid_high, ghost_low, ghost_high, t0, elapsed, gap, u(3)
  real(wp) :: worst_solid_margin, worst_ghost_margin, spread_ghost, spread_interior, worst_shift
  integer :: n_cells, size_index, trial, c, n_solid, count_min(3), count_max(3), interior_min(3), interior_max(3)
  integer :: shift(3), mismatches, n_fallback, n_records
  real(wp), parameter :: diameters(4) = [8.0_wp, 10.0_wp, 12.0_wp, 16.0_wp]
  character(len=160) :: line

  call parallel_start()
  call test_start('immersed_geometry')
  call stream_seed(stream, 10_i8, stream_id=7)
  image_options%image_point = 'image'

  ! --- Periodic minimum image.
  call check_close(minimum_image(0.9_wp, 1.0_wp), -0.1_wp, 1.0e-14_wp, 'minimum_image_wraps_down')
  call check_close(minimum_image(-0.7_wp, 1.0_wp), 0.3_wp, 1.0e-14_wp, 'minimum_image_wraps_up')
  call check_close(minimum_image(0.2_wp, 1.0_wp), 0.2_wp, 1.0e-14_wp, 'minimum_image_inside_unchanged')

  ! --- Spheres of D/dx = 8..16 at random sub-cell offsets, 32^3.
  ! Bounds (h = dx, R = D/2; each node owns the cube of side h around it, which lies within
  ! sqrt(3) h/2 of the node):
  !  - solid nodes: V(R - sqrt(3) h/2) <= N_solid h^3 <= V(R + sqrt(3) h/2), i.e. the solid count
  !    is within +-0.87 surface layers (4 pi R^2 sqrt(3)/2 h) of V/h^3 under any shift;
  !  - ghost nodes lie in the shell R - h <= |x| < R (the fluid neighbour is h away):
  !    N_ghost h^3 <= V(R + sqrt(3) h/2) - V(R - h - sqrt(3) h/2);
  !  - every grid line along the component's own axis whose chord is longer than 2h holds at least
  !    two solid nodes, and both ends of that run are ghost nodes: N_ghost >= 2 pi (rho - h/sqrt 2)^2/h^2
  !    with rho = sqrt(R^2 - h^2) (the lattice points of that disc).
  n_cells = 32
  call grid_create(grid, n_cells, n_cells, n_cells, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  dx = grid%dx
  errors = record_errors_t()
  worst_solid_margin = huge(1.0_wp)
  worst_ghost_margin = huge(1.0_wp)
  spread_ghost = 0.0_wp
  spread_interior = 0.0_wp
  do size_index = 1, size(diameters)
    diameter = diameters(size_index)
    r_cells = 0.5_wp * diameter
    one(1)%shape = make_spheroid('sphere', r_cells * dx, density)
    solid_low = 4.0_wp / 3.0_wp * pi * (r_cells - 0.5_wp * sqrt(3.0_wp))**3
    solid_high = 4.0_wp / 3.0_wp * pi * (r_cells + 0.5_wp * sqrt(3.0_wp))**3
    ghost_high = solid_high - 4.0_wp / 3.0_wp * pi * (r_cells - 1.0_wp - 0.5_wp * sqrt(3.0_wp))**3
    ghost_low = 2.0_wp * pi * (sqrt(r_cells**2 - 1.0_wp) - 1.0_wp / sqrt(2.0_wp))**2
    count_min = huge(1); count_max = 0; interior_min = huge(1); interior_max = 0
    do trial = 1, 8
      one(1)%centre = (0.5_wp * n_cells + [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]) * dx
      one(1)%orientation = random_orientation(stream)
      call classify_nodes(grid, one, mirror_options, geometry)
      call check_geometry_against_reference(grid, one, .true., geometry, errors)
      do c = 1, 3
        n_solid = geometry%component(c)%n_ghost + geometry%component(c)%n_interior
        worst_solid_margin = min(worst_solid_margin, n_solid - solid_low, solid_high - n_solid)
        worst_ghost_margin = min(worst_ghost_margin, geometry%component(c)%n_ghost - ghost_low, &
                                 ghost_high - geometry%component(c)%n_ghost)
        count_min(c) = min(count_min(c), geometry%component(c)%n_ghost)
        count_max(c) = max(count_max(c), geometry%component(c)%n_ghost)
        interior_min(c) = min(interior_min(c), geometry%component(c)%n_interior)
        interior_max(c) = max(interior_max(c), geometry%component(c)%n_interior)
      end do
    end do
    ! Spread under shifts in units of one surface layer, pi D^2 nodes.
    spread_ghost = max(spread_ghost, maxval(count_max - count_min) / (pi * diameter**2))
    spread_interior = max(spread_interior, maxval(interior_max - interior_min) / (pi * diameter**2))
    write(line, '(a,f5.1,a,3(i6,a,i6,2x),a,3(i6,a,i6,2x))') 'sphere D/dx ', diameter, ': ghosts (u, v, w) ', &
        (count_min(c), '-', count_max(c), c = 1, 3), 'interior ', (interior_min(c), '-', interior_max(c), c = 1, 3)
    write(*, '(a)') trim(line)
  end do
  call check_above(worst_solid_margin, 0.0_wp, 'sphere_solid_count_within_0.87_layer_of_volume')
  call check_above(worst_ghost_margin, 0.0_wp, 'sphere_ghost_count_between_line_and_shell_bounds')
  ! The ghost and interior counts move by less than one surface layer under sub-cell shifts (the
  ! solid-count bound above allows 1.73 layers; the measured spread is reported).
  call check_below(spread_ghost, 1.0_wp, 'sphere_ghost_count_spread_below_one_layer')
  call check_below(spread_interior, 1.0_wp, 'sphere_interior_count_spread_below_one_layer')
  write(*, '(a,2f8.4)') 'spread under shifts, in surface layers (ghost, interior): ', spread_ghost, spread_interior
  call report_errors(errors, 'sphere', .true.)

  ! --- The paper's needle and disk (r = 50 um, aspect 5) at random orientations and offsets,
  ! dx = 15.6 um (a 1 mm box at 64^3) on a 48^3 box; pure mirror and image point.
  call grid_create(grid, 48, 48, 48, 0.75e-3_wp, 0.75e-3_wp, 0.75e-3_wp)
  dx = grid%dx
  errors = record_errors_t()
  image_errors = record_errors_t()
  n_records = 0
  do trial = 1, 8
    if (mod(trial, 2) == 0) then
      one(1)%shape = make_spheroid('disk', paper_radius, density)
    else
      one(1)%shape = make_spheroid('needle', paper_radius, density)
    end if
    one(1)%centre = grid%lx * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    one(1)%orientation = random_orientation(stream)
    call classify_nodes(grid, one, mirror_options, geometry)
    call check_geometry_against_reference(grid, one, .true., geometry, errors)
    n_records = n_records + sum(geometry%component(:)%n_ghost)
    call classify_nodes(grid, one, image_options, geometry)
    call check_geometry_against_reference(grid, one, .false., geometry, image_errors)
  end do
  call report_errors(errors, 'needle_disk_mirror', .true.)
  call report_errors(image_errors, 'needle_disk_image', .false.)
  write(*, '(a,i0,a,i0,a,i0,a)') 'needle/disk: ghost nodes in stencils (weight > 0), mirror: ', errors%ghosts_in_stencils, &
      ', image point: ', image_errors%ghosts_in_stencils, ' (', n_records, ' ghost records)'
  write(*, '(a,i0,a,i0)') 'needle/disk: records with G in its own stencil, mirror: ', errors%self_in_stencils, &
      ', image point: ', image_errors%self_in_stencils
  ! The pure mirror's stencil holds ghost nodes and G itself (that is why its rows are coupled).
  call check_above(real(errors%self_in_stencils, wp), 1.0_wp, 'mirror_stencils_contain_G_itself')

  ! --- A body straddling the periodic wrap (in x, y and z) against the same body shifted by an
  ! integer number of cells into the interior: the same counts, and node by node the same records.
  one(1)%shape = make_spheroid('needle', paper_radius, density)
  one(1)%orientation = random_orientation(stream)
  one(1)%centre = [0.3_wp, grid%ny - 0.4_wp, 0.2_wp] * dx
  shift = [20, -23, 17]
  call classify_nodes(grid, one, mirror_options, geometry)
  one(1)%centre = one(1)%centre + shift * dx
  call classify_nodes(grid, one, mirror_options, shifted)
  call compare_shifted(geometry, shifted, shift, mismatches, worst_shift)
  call check_equal(mismatches, 0, 'wrap_straddling_same_counts_and_nodes_as_interior')
  call check_below(worst_shift, 1.0e-12_wp, 'wrap_straddling_same_records_as_interior_cells')

  ! --- Two spheres of D/dx = 10 in near contact: surface gap 0.5 dx (image segments enter the
  ! other body: fallback) and 1.1 dx (the pure mirror's |M - B| = d_G <= dx cannot reach it).
  errors = record_errors_t()
  do trial = 1, 2
    gap = merge(0.5_wp, 1.1_wp, trial == 1) * dx
    bodies(1)%shape = make_spheroid('sphere', 5.0_wp * dx, density)
    bodies(2)%shape = bodies(1)%shape
    u = [stream_normal(stream), stream_normal(stream), stream_normal(stream)]
    u = u / norm2(u)
    bodies(1)%centre = grid%lx * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
    bodies(2)%centre = bodies(1)%centre + (10.0_wp * dx + gap) * u
    call classify_nodes(grid, bodies, mirror_options, geometry)
    call check_geometry_against_reference(grid, bodies, .true., geometry, errors)
    n_fallback = sum(geometry%component(:)%n_fallback)
    write(*, '(a,f4.1,a,i0,a,3i6)') 'two spheres, gap ', gap / dx, ' dx: fallbacks ', n_fallback, &
        ', ghosts ', geometry%component(:)%n_ghost
    if (trial == 1) then
      call check_above(real(n_fallback, wp), 1.0_wp, 'near_contact_gap_0.5dx_fallbacks_counted')
    else
      call check_equal(n_fallback, 0, 'gap_1.1dx_no_fallback_for_pure_mirror')
    end if
  end do
  call report_errors(errors, 'two_spheres', .true.)

  ! --- Overlapping spheres (centres 0.8 D apart): a node inside both belongs to the body whose
  ! surface is nearer; the classification (solid = inside either) still equals the reference.
  errors = record_errors_t()
  bodies(1)%shape = make_spheroid('sphere', 5.0_wp * dx, density)
  bodies(2)%shape = bodies(1)%shape
  bodies(1)%centre = grid%lx * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
  bodies(2)%centre = bodies(1)%centre + 8.0_wp * dx * [0.6_wp, 0.0_wp, 0.8_wp]
  call classify_nodes(grid, bodies, mirror_options, geometry)
  call check_geometry_against_reference(grid, bodies, .true., geometry, errors)
  call check_equal(errors%status_mismatches + errors%list_mismatches, 0, 'overlap_status_equals_reference')
  call check_equal(wrong_owners(geometry, bodies), 0, 'overlap_nodes_belong_to_nearest_surface')
  write(*, '(a,3i5,a,3i5)') 'overlapping spheres: fallbacks ', geometry%component(:)%n_fallback, &
      '; of which surface point inside the other body ', geometry%component(:)%n_overlap
  call check_above(real(sum(geometry%component(:)%n_overlap), wp), 1.0_wp, 'overlap_surface_point_inside_other_counted')

  ! --- Thin dimension of the paper's disk (r = 50 um, aspect 1/5: thickness 2a = 2 r 5^(-2/3) =
  ! 34.2 um) on a 1 mm box: the immersed-boundary issue states 2.2 cells at 64^3 (2 figures), hence
  ! 4.4 and 8.8 at 128^3 and 256^3.
  one(1)%shape = make_spheroid('disk', paper_radius, density)
  do c = 1, 3
    n_cells = 32 * 2**c
    call grid_create(grid, n_cells, n_cells, n_cells, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
    write(line, '(a,i0)') 'disk_thin_dimension_cells_', n_cells
    call check_close(thin_dimension_cells(one(1)%shape, grid), 2.0_wp * paper_radius * 5.0_wp**(-2.0_wp / 3.0_wp) &
                     / grid%dx, 1.0e-12_wp, trim(line))
    call check_close(thin_dimension_cells(one(1)%shape, grid), 2.2_wp * 2**(c - 1), 0.01_wp, trim(line)//'_2_figures')
    write(*, '(a,i0,a,f6.3)') 'disk thickness at ', n_cells, '^3: ', thin_dimension_cells(one(1)%shape, grid)
  end do

  ! --- Cost at 128^3 with two bodies (needle and disk, random orientations), reported only.
  call grid_create(grid, 128, 128, 128, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  bodies(1)%shape = make_spheroid('needle', paper_radius, density)
  bodies(2)%shape = make_spheroid('disk', paper_radius, density)
  bodies(1)%centre = [0.3e-3_wp, 0.5e-3_wp, 0.5e-3_wp]
  bodies(2)%centre = [0.7e-3_wp, 0.5e-3_wp, 0.5e-3_wp]
  bodies(1)%orientation = random_orientation(stream)
  bodies(2)%orientation = random_orientation(stream)
  call classify_nodes(grid, bodies, mirror_options, geometry)
  t0 = wall_time()
  do trial = 1, 5
    call classify_nodes(grid, bodies, mirror_options, geometry)
  end do
  elapsed = (wall_time() - t0) / 5
  write(*, '(a,f8.2,a,3i7,a,3i7)') 'classification at 128^3, needle + disk: ', 1.0e3_wp * elapsed, ' ms; ghosts ', &
      geometry%component(:)%n_ghost, '; interior ', geometry%component(:)%n_interior
  call check(all(geometry%component(:)%n_ghost > 0), 'classification_128_two_bodies_runs')
  call test_finish()

contains

  subroutine report_errors(e, label, mirror)
    type(record_errors_t), intent(in) :: e
    character(len=*), intent(in) :: label
    logical, intent(in) :: mirror
    call check_equal(e%status_mismatches, 0, label//'_status_equals_brute_force_reference')
    call check_equal(e%list_mismatches, 0, label//'_lists_and_stencil_links_consistent')
    call check_equal(e%neighbour_violations, 0, label//'_ghosts_touch_fluid_interior_and_fluid_never_meet')
    call check_below(e%ghost_distance, 1.0e-12_wp, label//'_G_equals_B_minus_dG_n')
    call check_below(e%image_distance, 1.0e-12_wp, label//'_M_outside_at_dM_from_surface')
    if (mirror) call check_below(e%mirror, 1.0e-12_wp, label//'_M_equals_2B_minus_G')
    call check_below(e%weight_sum, 1.0e-14_wp, label//'_weights_nonnegative_sum_one')
    call check_below(e%linear_field, 1.0e-12_wp, label//'_stencil_exact_for_linear_field')
    call check_above(e%min_outside, 0.0_wp, label//'_M_outside_every_body')
  end subroutine report_errors

  !> Ghost and interior nodes whose body is not the one with the nearest surface among the bodies
  !> that contain them.
  integer function wrong_owners(geometry, bodies) result(wrong)
    type(immersed_geometry_t), intent(in) :: geometry
    type(immersed_body_t), intent(in) :: bodies(:)
    integer :: c, g, n, best
    real(wp) :: x(3), depth, best_depth, box(3)
    box = [grid%lx, grid%ly, grid%lz]
    wrong = 0
    do c = 1, 3
      do g = 1, geometry%component(c)%n_ghost + geometry%component(c)%n_interior
        if (g <= geometry%component(c)%n_ghost) then
          x = node_position(grid, c, geometry%component(c)%ghost(g)%node(1), geometry%component(c)%ghost(g)%node(2), &
                            geometry%component(c)%ghost(g)%node(3))
        else
          x = node_position(grid, c, geometry%component(c)%interior(1, g - geometry%component(c)%n_ghost), &
                            geometry%component(c)%interior(2, g - geometry%component(c)%n_ghost), &
                            geometry%component(c)%interior(3, g - geometry%component(c)%n_ghost))
        end if
        best = 0
        best_depth = huge(1.0_wp)
        do n = 1, size(bodies)
          ! Sphere: depth R - |x - centre| at the minimum image.
          depth = bodies(n)%shape%radius - norm2(minimum_image(x - bodies(n)%centre, box))
          if (depth > 0.0_wp .and. depth < best_depth) then
            best = n
            best_depth = depth
          end if
        end do
        if (g <= geometry%component(c)%n_ghost) then
          if (geometry%component(c)%ghost(g)%body /= best) wrong = wrong + 1
        else
          if (geometry%component(c)%interior_body(g - geometry%component(c)%n_ghost) /= best) wrong = wrong + 1
        end if
      end do
    end do
  end function wrong_owners

  !> Node-by-node comparison of a classification with the same body shifted by `shift` cells.
  subroutine compare_shifted(a, b, shift, mismatches, worst)
    type(immersed_geometry_t), intent(in) :: a, b
    integer, intent(in) :: shift(3)
    integer, intent(out) :: mismatches
    real(wp), intent(out) :: worst
    integer, allocatable :: index_b(:, :, :)
    integer :: c, g, node(3)
    mismatches = 0
    worst = 0.0_wp
    allocate(index_b(grid%nx, grid%ny, grid%nz))
    do c = 1, 3
      if (a%component(c)%n_ghost /= b%component(c)%n_ghost) mismatches = mismatches + 1
      if (a%component(c)%n_interior /= b%component(c)%n_interior) mismatches = mismatches + 1
      index_b = 0
      do g = 1, b%component(c)%n_ghost
        node = b%component(c)%ghost(g)%node
        index_b(node(1), node(2), node(3)) = g
      end do
      do g = 1, a%component(c)%n_ghost
        node = modulo(a%component(c)%ghost(g)%node + shift - 1, [grid%nx, grid%ny, grid%nz]) + 1
        if (index_b(node(1), node(2), node(3)) == 0) then
          mismatches = mismatches + 1
          cycle
        end if
        associate (ra => a%component(c)%ghost(g), rb => b%component(c)%ghost(index_b(node(1), node(2), node(3))))
          worst = max(worst, abs(ra%distance - rb%distance) / dx, &
                      maxval(abs((ra%surface_point - ra%position) - (rb%surface_point - rb%position))) / dx, &
                      maxval(abs((ra%image_point - ra%position) - (rb%image_point - rb%position))) / dx, &
                      maxval(abs(ra%weight - rb%weight)))
          if (any(ra%lower_offset /= rb%lower_offset) .or. ra%self_corner /= rb%self_corner) mismatches = mismatches + 1
        end associate
      end do
    end do
  end subroutine compare_shifted

end program test_immersed_geometry
