!> The narrow-band classification (immersed_options_t%band = .true., the default) against the full
!> one (band = .false.: every node of each body's bounding box tested exactly, every other body tried
!> by the fallback test), node by node and record by record, on random placements of a needle, a
!> disk and a sphere: anywhere (across the periodic wrap, overlapping or apart), in near contact
!> (gaps below two cells: fallback and saturated rows), at sub-cell centre offsets 0, 1/4, 1/2 of a
!> cell (surfaces through nodes) and random ones, for both image-point rules. The band geometry is
!> kept from one placement to the next (its work arrays reused, as a moving body's are), the full one
!> is classified afresh. Used by tests/unit/test_immersed_band.f90 (1 rank) and
!> tests/mpi/test_immersed_band_ranks.f90 (2 ranks); the checks are over all ranks.
module band_comparison
  use agglo_kinds, only: wp, i8
  use parallel_env, only: global_max, global_sum
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use quaternion, only: random_orientation
  use spheroid, only: make_spheroid
  use fluid_grid, only: fluid_grid_t, grid_create
  use immersed_geometry, only: immersed_body_t, immersed_options_t, immersed_geometry_t, component_nodes_t, &
                               ghost_node_t, classify_nodes
  use test_framework, only: check, check_below, check_above
  implicit none
  private
  public :: compare_band_with_full

  !> Differences found (over this rank's nodes) and what was compared.
  type :: differences_t
    integer :: status = 0            !< status-array entries (halo ring included) and list counts that differ
    integer :: lists = 0             !< ghost/interior list entries (node, body, order) that differ
    integer :: flags = 0             !< integer and logical record fields that differ (stencil, flags, bodies)
    real(wp) :: geometry = 0.0_wp    !< largest |difference| of a record's lengths and points (in cells) and unit quantities
    integer :: ghosts = 0, interior = 0, fallbacks = 0, saturated = 0, overlaps = 0   !< compared (full path)
  end type differences_t

contains

  !> Run the placements on this grid's ranks and print the checks (5 PASS/FAIL lines).
  subroutine compare_band_with_full(n_cells)
    integer, intent(in) :: n_cells
    real(wp), parameter :: density = 2710.0_wp
    real(wp), parameter :: offsets(4) = [0.0_wp, 0.25_wp, 0.5_wp, -1.0_wp]   ! -1: random
    type(fluid_grid_t) :: grid
    type(random_stream_t) :: stream
    type(immersed_options_t) :: band, full
    type(immersed_geometry_t) :: banded, reference
    type(immersed_body_t) :: bodies(3)
    type(differences_t) :: found
    real(wp) :: dx, direction(3), reach
    integer :: rule, placement, n, c, d
    character(len=120) :: detail

    ! The same stream on every rank: every rank places the same bodies.
    call stream_seed(stream, 34_i8, stream_id=11)
    call grid_create(grid, n_cells, n_cells, n_cells, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
    dx = grid%dx
    ! Sizes in cells as in the studies: D/dx = 10 for the sphere; needle and disk of aspect 5 with the
    ! volume of a sphere of D/dx = 8 (needle 2a = 23 cells, disk 2a = 2.7 cells thick).
    bodies(1)%shape = make_spheroid('needle', 4.0_wp * dx, density)
    bodies(2)%shape = make_spheroid('disk', 4.0_wp * dx, density)
    bodies(3)%shape = make_spheroid('sphere', 5.0_wp * dx, density)
    full%band = .false.
    do rule = 1, 2
      band%image_point = merge('mirror', 'image ', rule == 1)
      full%image_point = band%image_point
      do placement = 1, 16
        do n = 1, 3
          do d = 1, 3
            if (offsets(mod(placement - 1, 4) + 1) >= 0.0_wp) then
              bodies(n)%centre(d) = (floor(stream_uniform(stream) * n_cells) + offsets(mod(placement - 1, 4) + 1)) * dx
            else
              bodies(n)%centre(d) = stream_uniform(stream) * n_cells * dx
            end if
          end do
          bodies(n)%orientation = random_orientation(stream)
        end do
        if (placement > 8) then
          ! Near contact: the needle and the disk a little inside or outside the sum of their
          ! bounding radii from the sphere, along random directions.
          do n = 1, 2
            do d = 1, 3
              direction(d) = stream_uniform(stream) - 0.5_wp
            end do
            direction = direction / norm2(direction)
            reach = (bodies(3)%shape%a + min(bodies(n)%shape%a, bodies(n)%shape%b)) * (0.9_wp + 0.2_wp * &
                    stream_uniform(stream))
            bodies(n)%centre = bodies(3)%centre + reach * direction
          end do
        end if
        call classify_nodes(grid, bodies, band, banded)
        call classify_nodes(grid, bodies, full, reference)
        do c = 1, 3
          call compare_component(banded%component(c), reference%component(c), dx, found)
        end do
      end do
    end do

    write(detail, '(a,i0,a,i0,a,i0,a)') 'ghost records ', total(found%ghosts), ', interior nodes ', &
        total(found%interior), ', fallback rows ', total(found%fallbacks), ' compared'
    call check(total(found%status) == 0, 'band_status_equals_full', trim(detail))
    call check(total(found%lists) == 0, 'band_lists_equal_full', 'ghost and interior lists: node, body and order')
    call check(total(found%flags) == 0, 'band_record_fields_equal_full', &
               'stencil nodes, status, links, fallback/saturated flags, opposite body')
    ! Tolerance 1e-12 (cells, and for unit quantities): the same records to round-off (the task's
    ! criterion; the two paths evaluate each record by the same arithmetic, so 0 is expected).
    call check_below(global_max(found%geometry), 1.0e-12_wp, 'band_record_geometry_equals_full')
    ! Not vacuous: the placements produced fallback rows, saturated rows and overlaps on some rank.
    write(detail, '(a,3(i0,a))') 'fallback ', total(found%fallbacks), ', saturated ', total(found%saturated), &
        ', overlap ', total(found%overlaps), ' rows'
    call check(total(found%fallbacks) > 0 .and. total(found%saturated) > 0 .and. total(found%overlaps) > 0, &
               'band_cases_include_near_contact_and_overlap', trim(detail))
  end subroutine compare_band_with_full

  integer function total(local)
    integer, intent(in) :: local
    total = nint(global_sum(real(local, wp)))
  end function total

  subroutine compare_component(band, full, dx, found)
    type(component_nodes_t), intent(in) :: band, full
    real(wp), intent(in) :: dx
    type(differences_t), intent(inout) :: found
    integer :: g, m
    found%status = found%status + count(band%status /= full%status)
    if (band%n_ghost /= full%n_ghost .or. band%n_interior /= full%n_interior .or. &
        band%n_fallback /= full%n_fallback .or. band%n_overlap /= full%n_overlap .or. &
        band%n_saturated /= full%n_saturated .or. band%halo_planes_needed /= full%halo_planes_needed) then
      found%status = found%status + 1
      return
    end if
    found%ghosts = found%ghosts + full%n_ghost
    found%interior = found%interior + full%n_interior
    found%fallbacks = found%fallbacks + full%n_fallback
    found%saturated = found%saturated + full%n_saturated
    found%overlaps = found%overlaps + full%n_overlap
    do m = 1, full%n_interior
      if (any(band%interior(:, m) /= full%interior(:, m)) .or. band%interior_body(m) /= full%interior_body(m)) &
        found%lists = found%lists + 1
    end do
    do g = 1, full%n_ghost
      call compare_record(band%ghost(g), full%ghost(g), dx, found)
    end do
  end subroutine compare_component

  subroutine compare_record(band, full, dx, found)
    type(ghost_node_t), intent(in) :: band, full
    real(wp), intent(in) :: dx
    type(differences_t), intent(inout) :: found
    if (any(band%node /= full%node) .or. band%body /= full%body) then
      found%lists = found%lists + 1
      return
    end if
    if (any(band%lower_offset /= full%lower_offset) .or. any(band%stencil /= full%stencil) .or. &
        any(band%stencil_status /= full%stencil_status) .or. any(band%stencil_local .neqv. full%stencil_local) .or. &
        any(band%stencil_ghost /= full%stencil_ghost) .or. band%self_corner /= full%self_corner .or. &
        (band%fallback .neqv. full%fallback) .or. (band%saturated .neqv. full%saturated) .or. &
        band%opposite_body /= full%opposite_body) found%flags = found%flags + 1
    found%geometry = max(found%geometry, &
        maxval(abs(band%position - full%position)) / dx, &
        maxval(abs(band%surface_point - full%surface_point)) / dx, &
        maxval(abs(band%image_point - full%image_point)) / dx, &
        maxval(abs(band%opposite_point - full%opposite_point)) / dx, &
        abs(band%distance - full%distance) / dx, abs(band%image_distance - full%image_distance) / dx, &
        maxval(abs(band%normal - full%normal)), abs(band%extrapolation - full%extrapolation), &
        abs(band%couette_gain - full%couette_gain), maxval(abs(band%weight - full%weight)))
  end subroutine compare_record

end module band_comparison
