!> Immersed-boundary geometry: classification of the staggered (MAC) velocity nodes of each component
!> into fluid, ghost and interior nodes for N spheroids in the periodic box, and for every ghost node
!> its record (closest surface point, normal, image point and the trilinear interpolation stencil of
!> the image point on the component's own grid: module ghost_records) (docs/theory.md, "Immersed
!> boundary geometry").
!>
!> - A node is solid when it lies strictly inside a body (implicit function < 0, at the periodic
!>   minimum image of node - centre). It belongs to the body whose surface is nearest among those
!>   that contain it (only overlapping bodies contain a node twice).
!> - Ghost: a solid node with at least one fluid node among its 6 neighbours on the same
!>   component's grid. Interior: every other solid node. Fluid: not solid.
!> The node records' types are immersed_nodes' (re-exported here, with node_position and
!> thin_dimension_cells), so a user of the geometry needs this module only.
!>
!> Work per body (options%band): the exact tests run only where a cheap one cannot decide, so the
!> classification gives the nodes and records of the full one (every node of each body's bounding
!> box tested exactly, every other body tried for the fallback) with work in proportion to the
!> body's nodes rather than to the grid:
!> - solid test: along each row of nodes (fixed j, k) the implicit function of the rotated body is a
!>   quadratic q(s) = A11 s^2 + 2 b s + c in the x separation s (x^T A x - 1, A = R diag(a^-2, b^-2,
!>   b^-2) R^T). A row whose minimum exceeds the margin is skipped; a node with |q| above the margin
!>   takes the sign of q; only the nodes within the margin take the exact test on the rotated point.
!>   The margin, 1e-9 (max(a, b)/min(a, b))^2, exceeds the round-off of either evaluation (at most
!>   some tens of ulps of the terms, each below 9 (max/min)^2 in the bounding box) by orders of
!>   magnitude, so both give the same sign wherever the cheap one is trusted;
!>   The nodes within the margin lie between the roots of q(s) = margin: each row visits only the
!>   box's nodes there (one more each side for the roots' round-off), and records them as the row's
!>   candidate run for that body. The runs hold every node a body can own, so the ghost test, the
!>   lists and the reset of the work arrays visit the runs alone: the work per body goes with its
!>   rows times its chords, not with its bounding box;
!> - the ghost and interior lists are gathered plane by plane and row by row from the rows' runs
!>   (the union of a row's runs in ascending index: storage order, as a sweep of the whole slab would);
!> - the fallback test of a ghost tries only the bodies whose bounding sphere comes within reach r
!>   of its body: |c_m - c_n| <= R_n + R_m + r and the distance from c_m to the (analytic) solid n
!>   at most R_m + r, r = (1 + max(1, image_cells)) h_max, R = max(a, b); any other body is rejected
!>   by the segment test's own bounding-sphere check, since the segment starts at B in the solid n
!>   (on the analytic surface, or on a mesh inscribed in it) and is at most r - h_max long. The
!>   second test matters for elongated bodies, whose bounding spheres overlap many neighbours';
!> - the closest point is the Newton iteration of spheroid_distance (about 5 evaluations for a ghost
!>   node within a cell of the surface).
!>
!> The classification is local: each rank classifies its own z planes and as many planes beyond
!> them as the stencils reach (the geometry is analytic, so no communication is needed). Stencil
!> nodes are stored by global index, wrapped periodically; the ones outside this rank's planes
!> need values from the neighbouring ranks (`halo_planes_needed`).
module immersed_geometry
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use periodic_box, only: minimum_image
  use fluid_grid, only: fluid_grid_t
  use quaternion, only: rotate_to_body, rotation_matrix
  use spheroid, only: implicit_function, support_value
  use spheroid_distance, only: surface_projection_t, body_closest_point
  use mesh_distance, only: mesh_contains
  use immersed_nodes, only: immersed_body_t, immersed_options_t, ghost_node_t, component_nodes_t, node_position, &
                            thin_dimension_cells, wrap, node_fluid, node_ghost, node_interior
  use ghost_records, only: build_ghost_record
  implicit none
  private
  public :: immersed_body_t, immersed_options_t, ghost_node_t, component_nodes_t, immersed_geometry_t
  public :: classify_nodes, node_position, thin_dimension_cells, fallback_count, saturated_count
  public :: node_fluid, node_ghost, node_interior

  !> Work arrays of the classification, kept between calls so that a reclassification (every step
  !> of a moving body) neither allocates nor sweeps the whole slab: between calls every entry is
  !> zero (fluid), and after each component only the boxes the bodies marked are zeroed again.
  type :: classification_work_t
    integer :: k_first = 0                              !< lowest extended local plane of owner
    integer, allocatable :: owner(:, :, :)              !< (nx, ny, k_first:) body containing the node, else 0
    integer(int8), allocatable :: status(:, :, :)       !< (nx, ny, k_first + 1:) node_fluid/ghost/interior
    integer, allocatable :: ghost_index(:, :, :)        !< (nx, ny, nz_local) index in the ghost list, else 0
    !> the x and y index sets of each body's bounding box, (nx | ny, n_bodies)
    logical, allocatable :: marked_x(:, :), marked_y(:, :)
    !> walk_x(1:walk_length(n), n): the x indices of body n's box in increasing separation from its
    !> centre (a periodic run of less than half the box)
    integer, allocatable :: walk_x(:, :), walk_length(:)
    !> the candidate runs: along row (run_j, run_k) the positions run_first..run_last of
    !> run_body's walk, the only nodes of the row that can lie in that body; together they hold
    !> every node owner marks, so the later passes visit them alone
    integer :: n_runs = 0
    integer, allocatable :: run_body(:), run_j(:), run_k(:), run_first(:), run_last(:)
    !> the runs of each local row (ny, nz_local): row_head(j, k) the last one added, run_next(r)
    !> the one added before r (0: none)
    integer, allocatable :: row_head(:, :), run_next(:)
  end type classification_work_t

  !> The immersed-boundary geometry of all bodies on this rank.
  type :: immersed_geometry_t
    integer :: n_bodies = 0
    type(component_nodes_t) :: component(3)
    type(classification_work_t) :: work                 !< reused by every classification
    !> classifications so far: what is derived from the records (the packed ghost rows of the
    !> imposition) is stale when it was derived at another count; code that edits records by hand counts too
    integer :: classifications = 0
  end type immersed_geometry_t

contains

  !> Ghost nodes of this rank (all three components) whose image point was moved back because its
  !> segment entered another body (the fallback of the module header; overlaps included).
  pure integer function fallback_count(geometry)
    type(immersed_geometry_t), intent(in) :: geometry
    fallback_count = sum(geometry%component(:)%n_fallback)
  end function fallback_count

  !> Ghost rows of all components on this rank that take the saturated Couette value (a gap below
  !> the saturation gap; a subset of the fallback rows).
  pure integer function saturated_count(geometry)
    type(immersed_geometry_t), intent(in) :: geometry
    saturated_count = sum(geometry%component(:)%n_saturated)
  end function saturated_count

  !> Classify the nodes of u, v and w on this rank for the bodies and build the ghost records.
  subroutine classify_nodes(grid, bodies, options, geometry)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    type(immersed_options_t), intent(in) :: options
    type(immersed_geometry_t), intent(inout) :: geometry
    integer :: component
    integer, allocatable :: candidates(:, :), n_candidates(:)
    call check_inputs(grid, bodies, options)
    geometry%n_bodies = size(bodies)
    geometry%classifications = geometry%classifications + 1
    ! The bodies each body's fallback test tries: the same for the three components.
    call fallback_candidates(grid, bodies, options, candidates, n_candidates)
    do component = 1, 3
      call classify_component(grid, bodies, options, component, candidates, n_candidates, geometry%work, &
                              geometry%component(component))
    end do
  end subroutine classify_nodes

  subroutine check_inputs(grid, bodies, options)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    type(immersed_options_t), intent(in) :: options
    real(wp) :: box(3), extent(3)
    integer :: n, d
    character(len=200) :: text
    select case (trim(options%image_point))
    case ('mirror', 'image')
    case default
      call fatal('immersed geometry: image_point = '''//trim(options%image_point)//'''; allowed: mirror, image')
    end select
    if (.not. (options%image_distance_cells >= 1.0_wp .and. options%image_distance_cells <= 4.0_wp)) then
      write(text, '(a,es12.5,a)') 'immersed geometry: image_distance_cells = ', options%image_distance_cells, &
          '; allowed: 1 to 4 cells'
      call fatal(trim(text))
    end if
    box = [grid%lx, grid%ly, grid%lz]
    do n = 1, size(bodies)
      extent = lab_half_extent(bodies(n))
      do d = 1, 3
        ! The minimum image sees one copy of a body only if it spans less than half the box.
        if (.not. (extent(d) < 0.5_wp * box(d) - max(grid%dx, grid%dy, grid%dz))) then
          write(text, '(a,i0,a,es12.5,a,i0,a,es12.5,a)') 'immersed geometry: body ', n, ' extends ', extent(d), &
              ' m from its centre along axis ', d, '; it must be less than half the box less one cell (', &
              0.5_wp * box(d) - max(grid%dx, grid%dy, grid%dz), ' m)'
          call fatal(trim(text))
        end if
      end do
    end do
  end subroutine check_inputs

  !> Half-extents (m) of a body along the lab axes: the support function along each axis.
  pure function lab_half_extent(body) result(extent)
    type(immersed_body_t), intent(in) :: body
    real(wp) :: extent(3), lab_axes_in_body(3, 3)
    integer :: d
    lab_axes_in_body = transpose(rotation_matrix(body%orientation))   ! column d: R^T e_d
    do d = 1, 3
      extent(d) = support_value(body%shape, lab_axes_in_body(:, d))
    end do
  end function lab_half_extent

  subroutine classify_component(grid, bodies, options, component, candidates, n_candidates, work, nodes)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    type(immersed_options_t), intent(in) :: options
    integer, intent(in) :: component
    integer, intent(in) :: candidates(:, :), n_candidates(:)   !< fallback_candidates
    type(classification_work_t), intent(inout) :: work
    type(component_nodes_t), intent(inout) :: nodes
    integer, allocatable :: list_x(:), list_y(:), list_z(:)
    logical, allocatable :: near_x(:), near_y(:), near_z(:)
    integer :: reach, k_lo, k_hi, i, j, k, ii, jj, kk, n_ghost, n_interior, g, n, n_row, r, p
    integer :: row_indices(grid%nx), i_below(grid%nx), i_above(grid%nx)
    integer :: j_below(grid%ny), j_above(grid%ny)
    real(wp) :: h_max, h_min, image_cells

    ! Planes beyond the slab that the stencils can reach: d_G <= h_max (a fluid neighbour lies one
    ! spacing away), so |M - G| <= (1 + max(1, image_cells)) h_max, plus the stencil's upper corner.
    h_max = max(grid%dx, grid%dy, grid%dz)
    h_min = min(grid%dx, grid%dy, grid%dz)
    image_cells = 1.0_wp
    if (trim(options%image_point) == 'image') image_cells = max(1.0_wp, options%image_distance_cells)
    reach = ceiling((1.0_wp + image_cells) * h_max / h_min) + 1
    i_below = [(wrap(i - 1, grid%nx), i = 1, grid%nx)]
    i_above = [(wrap(i + 1, grid%nx), i = 1, grid%nx)]
    j_below = [(wrap(j - 1, grid%ny), j = 1, grid%ny)]
    j_above = [(wrap(j + 1, grid%ny), j = 1, grid%ny)]
    k_lo = 1 - reach
    k_hi = grid%nz_local + reach

    ! Solid owner on the planes the ghost test of every stencil node needs (one more each side);
    ! near_* mark the indices within some body's bounding box: only there can a node be solid.
    call prepare_work(work, grid, size(bodies), k_lo - 1, k_hi + 1)
    allocate(near_x(grid%nx), near_y(grid%ny), near_z(k_lo - 1:k_hi + 1))
    call mark_solid_nodes(grid, bodies, options, component, work, near_x, near_y, near_z)

    associate (owner => work%owner, status => work%status)
      ! status is node_fluid everywhere on entry (work's invariant); solid nodes only in the runs,
      ! each visited once, in its owner's run. The counts are of this rank's planes.
      n_ghost = 0
      n_interior = 0
      do r = 1, work%n_runs
        n = work%run_body(r)
        j = work%run_j(r)
        k = work%run_k(r)
        if (k < k_lo .or. k > k_hi) cycle
        do p = work%run_first(r), work%run_last(r)
          i = work%walk_x(p, n)
          if (owner(i, j, k) /= n) cycle
          if (owner(i_below(i), j, k) == 0 .or. owner(i_above(i), j, k) == 0 .or. &
              owner(i, j_below(j), k) == 0 .or. owner(i, j_above(j), k) == 0 .or. &
              owner(i, j, k - 1) == 0 .or. owner(i, j, k + 1) == 0) then
            status(i, j, k) = node_ghost
            if (k >= 1 .and. k <= grid%nz_local) n_ghost = n_ghost + 1
          else
            status(i, j, k) = node_interior
            if (k >= 1 .and. k <= grid%nz_local) n_interior = n_interior + 1
          end if
        end do
      end do

      call clear_field_status(grid, nodes)

      ! Lists of this rank's ghost and interior nodes, in storage order (k, then j, then i).
      nodes%component = component
      ! The lists keep their storage while it holds the new counts (n_ghost, n_interior say how much
      ! is in use): a moving body changes its counts by a few nodes a step, and a new list of ghost
      ! records (each initialised) every step cost as much as a tenth of the classification.
      if (allocated(nodes%ghost)) then
        if (size(nodes%ghost) < n_ghost) deallocate(nodes%ghost)
      end if
      if (allocated(nodes%interior)) then
        if (size(nodes%interior, 2) < n_interior) deallocate(nodes%interior, nodes%interior_body)
      end if
      if (.not. allocated(nodes%ghost)) allocate(nodes%ghost(n_ghost + n_ghost / 8))
      if (.not. allocated(nodes%interior)) allocate(nodes%interior(3, n_interior + n_interior / 8), &
                                                    nodes%interior_body(n_interior + n_interior / 8))
      nodes%n_ghost = 0
      nodes%n_interior = 0
      if (options%band) then
        ! Plane by plane, row by row: only the rows with candidate runs, and in a row the indices
        ! of its runs, ascending and each once (the order of the sweep below).
        do k = 1, grid%nz_local
          if (.not. near_z(k)) cycle
          do j = 1, grid%ny
            if (work%row_head(j, k) == 0) cycle
            n_row = 0
            r = work%row_head(j, k)
            do while (r /= 0)
              do p = work%run_first(r), work%run_last(r)
                call insert_index(work%walk_x(p, work%run_body(r)), row_indices, n_row)
              end do
              r = work%run_next(r)
            end do
            do ii = 1, n_row
              call list_node(row_indices(ii), j, k)
            end do
          end do
        end do
      else
        ! Every node of the union of the boxes' index sets (the reference), in storage order.
        list_x = pack([(i, i = 1, grid%nx)], near_x)
        list_y = pack([(j, j = 1, grid%ny)], near_y)
        list_z = pack([(k, k = k_lo, k_hi)], near_z(k_lo:k_hi))
        do kk = 1, size(list_z)
          k = list_z(kk)
          if (k < 1 .or. k > grid%nz_local) cycle
          do jj = 1, size(list_y)
            do ii = 1, size(list_x)
              call list_node(list_x(ii), list_y(jj), k)
            end do
          end do
        end do
      end if
      call fill_field_status(grid, status, k_lo, nodes)

      nodes%n_fallback = 0
      nodes%n_overlap = 0
      nodes%n_saturated = 0
      nodes%halo_planes_needed = 0
      ! The ghost list's index of each local ghost node, for the stencils' ghost links (zeroed after).
      do g = 1, nodes%n_ghost
        work%ghost_index(nodes%ghost(g)%node(1), nodes%ghost(g)%node(2), nodes%ghost(g)%node(3)) = g
      end do
      do g = 1, nodes%n_ghost
        n = nodes%ghost(g)%body
        call build_ghost_record(grid, bodies, options, component, status, k_lo, work%ghost_index, &
                                candidates(1:n_candidates(n), n), nodes%ghost(g))
        if (nodes%ghost(g)%fallback) nodes%n_fallback = nodes%n_fallback + 1
        if (nodes%ghost(g)%fallback .and. nodes%ghost(g)%image_distance <= 0.0_wp) nodes%n_overlap = nodes%n_overlap + 1
        if (nodes%ghost(g)%saturated) nodes%n_saturated = nodes%n_saturated + 1
        k = nodes%ghost(g)%node(3) + nodes%ghost(g)%lower_offset(3)
        nodes%halo_planes_needed = max(nodes%halo_planes_needed, 1 - k, k + 1 - grid%nz_local)
      end do
      do g = 1, nodes%n_ghost
        work%ghost_index(nodes%ghost(g)%node(1), nodes%ghost(g)%node(2), nodes%ghost(g)%node(3)) = 0
      end do
    end associate
    call clear_runs(work)
  contains

    !> Node (i, j, k) into the ghost or interior list by its status.
    subroutine list_node(i, j, k)
      integer, intent(in) :: i, j, k
      select case (work%status(i, j, k))
      case (node_ghost)
        nodes%n_ghost = nodes%n_ghost + 1
        ! Node and body only: build_ghost_record sets every other field.
        nodes%ghost(nodes%n_ghost)%node = [i, j, k]
        nodes%ghost(nodes%n_ghost)%body = work%owner(i, j, k)
      case (node_interior)
        nodes%n_interior = nodes%n_interior + 1
        nodes%interior(:, nodes%n_interior) = [i, j, k]
        nodes%interior_body(nodes%n_interior) = work%owner(i, j, k)
      end select
    end subroutine list_node
  end subroutine classify_component

  !> Insert index i into the ascending list(1:count) unless it is there already. The runs of a row
  !> come nearly in order and are short (a body's chord in cells), so the search from the end is short.
  pure subroutine insert_index(i, list, count)
    integer, intent(in) :: i
    integer, intent(inout) :: list(:), count
    integer :: position
    position = count
    do while (position > 0)
      if (list(position) <= i) exit
      position = position - 1
    end do
    if (position > 0) then
      if (list(position) == i) return
    end if
    list(position + 2:count + 1) = list(position + 1:count)
    list(position + 1) = i
    count = count + 1
  end subroutine insert_index

  !> For each body n, the other bodies its ghosts' fallback test must try (candidates(1:count(n), n),
  !> ascending): with options%band only those whose bounding sphere can meet an image segment from
  !> n's surface (the module header: two bounding spheres, then m's against the solid n), else all.
  subroutine fallback_candidates(grid, bodies, options, candidates, counts)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    type(immersed_options_t), intent(in) :: options
    integer, allocatable, intent(out) :: candidates(:, :), counts(:)
    real(wp) :: box(3), h_max, reach, radius(size(bodies)), separation(3)
    type(surface_projection_t) :: projection
    integer :: n, m
    box = [grid%lx, grid%ly, grid%lz]
    h_max = max(grid%dx, grid%dy, grid%dz)
    ! The longest image segment, max(d_G, image_cells h_max) with d_G <= h_max, and one cell more.
    reach = (1.0_wp + max(1.0_wp, merge(options%image_distance_cells, 1.0_wp, trim(options%image_point) == 'image'))) &
            * h_max
    radius = max(bodies(:)%shape%a, bodies(:)%shape%b)
    allocate(candidates(max(1, size(bodies) - 1), size(bodies)), counts(size(bodies)))
    counts = 0
    do n = 1, size(bodies)
      do m = 1, size(bodies)
        if (m == n) cycle
        if (options%band) then
          separation = minimum_image(bodies(m)%centre - bodies(n)%centre, box)
          if (norm2(separation) > radius(n) + radius(m) + reach) cycle
          projection = body_closest_point(bodies(n)%shape, rotate_to_body(bodies(n)%orientation, separation))
          if (projection%signed_distance > radius(m) + reach) cycle
        end if
        counts(n) = counts(n) + 1
        candidates(counts(n), n) = m
      end do
    end do
  end subroutine fallback_candidates

  !> Work arrays for owner planes k_first..k_last (allocated, all zero, when the grid or the
  !> reach changed; else kept, zero by the invariant) and the body boxes' marks.
  subroutine prepare_work(work, grid, n_bodies, k_first, k_last)
    type(classification_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: n_bodies, k_first, k_last
    logical :: fits
    fits = allocated(work%owner)
    if (fits) fits = size(work%owner, 1) == grid%nx .and. size(work%owner, 2) == grid%ny .and. &
                     lbound(work%owner, 3) == k_first .and. ubound(work%owner, 3) == k_last
    if (.not. fits) then
      if (allocated(work%owner)) deallocate(work%owner, work%status, work%ghost_index, work%row_head)
      allocate(work%owner(grid%nx, grid%ny, k_first:k_last), work%status(grid%nx, grid%ny, k_first + 1:k_last - 1))
      allocate(work%ghost_index(grid%nx, grid%ny, grid%nz_local), work%row_head(grid%ny, grid%nz_local))
      work%owner = 0
      work%row_head = 0
      work%status = node_fluid
      work%ghost_index = 0
      work%k_first = k_first
    end if
    if (allocated(work%marked_x)) then
      if (size(work%marked_x, 2) /= n_bodies .or. .not. fits) deallocate(work%marked_x, work%marked_y, &
                                                                        work%walk_x, work%walk_length)
    end if
    if (.not. allocated(work%marked_x)) allocate(work%marked_x(grid%nx, n_bodies), work%marked_y(grid%ny, n_bodies), &
                                                 work%walk_x(grid%nx, n_bodies), work%walk_length(n_bodies))
    if (.not. allocated(work%run_body)) allocate(work%run_body(0), work%run_j(0), work%run_k(0), work%run_first(0), &
                                                 work%run_last(0), work%run_next(0))
    work%marked_x = .false.
    work%marked_y = .false.
  end subroutine prepare_work

  !> Zero owner, status and the row lists along the candidate runs, which hold every node the
  !> classification marked (restores the work's invariant).
  subroutine clear_runs(work)
    type(classification_work_t), intent(inout) :: work
    integer :: r, p, j, k
    logical :: has_status
    do r = 1, work%n_runs
      j = work%run_j(r)
      k = work%run_k(r)
      has_status = k >= lbound(work%status, 3) .and. k <= ubound(work%status, 3)
      associate (walk => work%walk_x(:, work%run_body(r)))
        do p = work%run_first(r), work%run_last(r)
          work%owner(walk(p), j, k) = 0
          if (has_status) work%status(walk(p), j, k) = node_fluid
        end do
      end associate
      if (k >= lbound(work%row_head, 2) .and. k <= ubound(work%row_head, 2)) work%row_head(j, k) = 0
    end do
    work%n_runs = 0
  end subroutine clear_runs

  !> The field-layout status (0:nx+1, 0:ny+1, 0:nz_local+1) back to fluid: allocated when its shape
  !> changed; else only where the last classification put solid nodes (its ghost and interior
  !> lists with their halo-ring copies, and the two planes beyond the slab).
  subroutine clear_field_status(grid, nodes)
    type(fluid_grid_t), intent(in) :: grid
    type(component_nodes_t), intent(inout) :: nodes
    integer :: m
    logical :: fits
    fits = allocated(nodes%status)
    if (fits) fits = all(lbound(nodes%status) == 0) .and. all(ubound(nodes%status) == [grid%nx + 1, grid%ny + 1, &
                                                                                          grid%nz_local + 1])
    if (.not. fits) then
      if (allocated(nodes%status)) deallocate(nodes%status)
      allocate(nodes%status(0:grid%nx + 1, 0:grid%ny + 1, 0:grid%nz_local + 1))
      nodes%status = node_fluid
      return
    end if
    do m = 1, nodes%n_ghost
      call set_with_ring(nodes%status, nodes%ghost(m)%node, node_fluid)
    end do
    do m = 1, nodes%n_interior
      call set_with_ring(nodes%status, nodes%interior(:, m), node_fluid)
    end do
    nodes%status(:, :, 0) = node_fluid
    nodes%status(:, :, grid%nz_local + 1) = node_fluid
  end subroutine clear_field_status

  !> The field-layout status from the new lists, the planes beyond the slab and the periodic ring.
  subroutine fill_field_status(grid, status, k_lo, nodes)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: k_lo
    integer(int8), intent(in) :: status(:, :, k_lo:)
    type(component_nodes_t), intent(inout) :: nodes
    integer :: m, k, nzl
    nzl = grid%nz_local
    do m = 1, nodes%n_ghost
      call set_with_ring(nodes%status, nodes%ghost(m)%node, node_ghost)
    end do
    do m = 1, nodes%n_interior
      call set_with_ring(nodes%status, nodes%interior(:, m), node_interior)
    end do
    do k = 0, nzl + 1, nzl + 1
      nodes%status(1:grid%nx, 1:grid%ny, k) = status(:, :, k)
      nodes%status(0, 1:grid%ny, k) = nodes%status(grid%nx, 1:grid%ny, k)
      nodes%status(grid%nx + 1, 1:grid%ny, k) = nodes%status(1, 1:grid%ny, k)
      nodes%status(:, 0, k) = nodes%status(:, grid%ny, k)
      nodes%status(:, grid%ny + 1, k) = nodes%status(:, 1, k)
    end do
  end subroutine fill_field_status

  !> status(i, j, k) = value at node (i, j, k) (i, j in 1..n, k local) and at its copies on the
  !> periodic halo ring (i = 0 is i = nx, i = nx + 1 is i = 1; likewise j; corners included).
  pure subroutine set_with_ring(status, node, value)
    integer(int8), intent(inout) :: status(0:, 0:, 0:)
    integer, intent(in) :: node(3)
    integer(int8), intent(in) :: value
    integer :: i_copies(2), j_copies(2), a, b, nx, ny
    nx = ubound(status, 1) - 1
    ny = ubound(status, 2) - 1
    if (node(1) > 1 .and. node(1) < nx .and. node(2) > 1 .and. node(2) < ny) then   ! no copy on the ring
      status(node(1), node(2), node(3)) = value
      return
    end if
    i_copies = node(1)
    if (node(1) == nx) i_copies(2) = 0
    if (node(1) == 1) i_copies(2) = nx + 1
    j_copies = node(2)
    if (node(2) == ny) j_copies(2) = 0
    if (node(2) == 1) j_copies(2) = ny + 1
    do b = 1, 2
      do a = 1, 2
        status(i_copies(a), j_copies(b), node(3)) = value
      end do
    end do
  end subroutine set_with_ring

  !> work%owner(i, j, k) = index of the body that contains node (i, j, k) (k local, extended), else
  !> 0 (zero on entry). Only the nodes within each body's lab bounding box are tested, and with the
  !> band only those of each row's candidate run (work%run_*, module header); the box's x and y
  !> index sets go to work%marked_*, and the union of all boxes to near_*.
  subroutine mark_solid_nodes(grid, bodies, options, component, work, near_x, near_y, near_z)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    type(immersed_options_t), intent(in) :: options
    integer, intent(in) :: component
    type(classification_work_t), intent(inout) :: work
    logical, intent(out) :: near_x(:), near_y(:), near_z(work%k_first:)
    integer :: n, i, j, k, p, previous, p_first, p_last
    real(wp) :: box(3), extent(3), x(3), d(3), d_previous, d_new, rotation(3, 3), form(3, 3), margin, q, row_b, row_c
    real(wp) :: sep_x(grid%nx), sep_y(grid%ny), root, first_sep
    type(surface_projection_t) :: p_new, p_old

    box = [grid%lx, grid%ly, grid%lz]
    near_x = .false.
    near_y = .false.
    near_z = .false.
    work%n_runs = 0
    associate (owner => work%owner, in_x => work%marked_x, in_y => work%marked_y, walk => work%walk_x)
      do n = 1, size(bodies)
        extent = lab_half_extent(bodies(n))
        rotation = rotation_matrix(bodies(n)%orientation)
        ! The lab quadratic form A = R diag(a^-2, b^-2, b^-2) R^T and the margin of the row test
        ! (module header, "Work per body").
        form = matmul(rotation * spread([1.0_wp / bodies(n)%shape%a**2, 1.0_wp / bodies(n)%shape%b**2, &
                                         1.0_wp / bodies(n)%shape%b**2], 1, 3), transpose(rotation))
        margin = 1.0e-9_wp * (max(bodies(n)%shape%a, bodies(n)%shape%b) / min(bodies(n)%shape%a, bodies(n)%shape%b))**2
        do i = 1, grid%nx
          x = node_position(grid, component, i, 1, 1)
          sep_x(i) = minimum_image(x(1) - bodies(n)%centre(1), box(1))
          in_x(i, n) = abs(sep_x(i)) <= extent(1)
          near_x(i) = near_x(i) .or. in_x(i, n)
        end do
        call box_walk(in_x(:, n), walk(:, n), work%walk_length(n))
        if (work%walk_length(n) == 0) cycle   ! no node between the box's x planes
        first_sep = sep_x(walk(1, n))
        do j = 1, grid%ny
          x = node_position(grid, component, 1, j, 1)
          sep_y(j) = minimum_image(x(2) - bodies(n)%centre(2), box(2))
          in_y(j, n) = abs(sep_y(j)) <= extent(2)
          near_y(j) = near_y(j) .or. in_y(j, n)
        end do
        do k = lbound(owner, 3), ubound(owner, 3)
          x = node_position(grid, component, 1, 1, k)
          d(3) = minimum_image(x(3) - bodies(n)%centre(3), box(3))
          if (abs(d(3)) > extent(3)) cycle
          near_z(k) = .true.
          do j = 1, grid%ny
            if (.not. in_y(j, n)) cycle
            d(2) = sep_y(j)
            ! x^T A x - 1 along the row: q(s) = A11 s^2 + 2 row_b s + row_c; skip a row it misses.
            row_b = form(1, 2) * d(2) + form(1, 3) * d(3)
            row_c = (form(2, 2) * d(2) + 2.0_wp * form(2, 3) * d(3)) * d(2) + form(3, 3) * d(3)**2 - 1.0_wp
            if (options%band) then
              if (row_c - row_b**2 / form(1, 1) > margin) cycle
              ! q(s) <= margin only between the roots of q(s) = margin: the walk's positions there,
              ! one more each side for the roots' round-off (q itself decides each node below).
              root = sqrt(max(0.0_wp, row_b**2 - form(1, 1) * (row_c - margin)))
              p_first = max(1, floor(((-row_b - root) / form(1, 1) - first_sep) / grid%dx))
              p_last = min(work%walk_length(n), ceiling(((-row_b + root) / form(1, 1) - first_sep) / grid%dx) + 2)
            else
              p_first = 1
              p_last = work%walk_length(n)
            end if
            if (p_first > p_last) cycle
            call add_run(work, grid, n, j, k, p_first, p_last)
            do p = p_first, p_last
              i = walk(p, n)
              d(1) = sep_x(i)
              if (options%band) then
                q = (form(1, 1) * d(1) + 2.0_wp * row_b) * d(1) + row_c
                if (q > margin) cycle
              else
                q = 0.0_wp
              end if
              ! Inside test on the body-frame point R^T d (within the margin, or every node without the band).
              if (abs(q) <= margin) then
                if (.not. (implicit_function(bodies(n)%shape, matmul(d, rotation)) < 0.0_wp)) cycle
              end if
              if (bodies(n)%mesh%level >= 0) then   ! the mesh lies inside the spheroid
                if (.not. mesh_contains(bodies(n)%mesh, matmul(d, rotation))) cycle
              end if
              previous = owner(i, j, k)
              if (previous == 0) then
                owner(i, j, k) = n
              else
                ! Inside two (overlapping) bodies: the one whose surface is nearer.
                p_new = body_closest_point(bodies(n)%shape, rotate_to_body(bodies(n)%orientation, d))
                x = node_position(grid, component, i, j, k)
                p_old = body_closest_point(bodies(previous)%shape, rotate_to_body(bodies(previous)%orientation, &
                                           minimum_image(x - bodies(previous)%centre, box)))
                d_new = abs(p_new%signed_distance)
                d_previous = abs(p_old%signed_distance)
                if (d_new < d_previous) owner(i, j, k) = n
              end if
            end do
          end do
        end do
      end do
    end associate
  end subroutine mark_solid_nodes

  !> The indices where `inside` holds, a periodic run shorter than the period, from its lower end
  !> (the one whose periodic predecessor is outside) upwards: in increasing separation from the
  !> centre of the box they come from.
  pure subroutine box_walk(inside, walk, length)
    logical, intent(in) :: inside(:)
    integer, intent(out) :: walk(:), length
    integer :: i, start, n
    n = size(inside)
    length = 0
    start = 0
    do i = 1, n
      if (inside(i) .and. .not. inside(wrap(i - 1, n))) then
        start = i
        exit
      end if
    end do
    if (start == 0) return
    i = start
    do while (inside(i) .and. length < n)
      length = length + 1
      walk(length) = i
      i = wrap(i + 1, n)
    end do
  end subroutine box_walk

  !> Record the candidate run of body n along row (j, k) (module header of the work type); a run on
  !> this rank's planes joins its row's list.
  subroutine add_run(work, grid, n, j, k, first, last)
    type(classification_work_t), intent(inout) :: work
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: n, j, k, first, last
    integer :: r
    if (work%n_runs == size(work%run_body)) call grow_runs(work)
    r = work%n_runs + 1
    work%n_runs = r
    work%run_body(r) = n
    work%run_j(r) = j
    work%run_k(r) = k
    work%run_first(r) = first
    work%run_last(r) = last
    work%run_next(r) = 0
    if (k >= 1 .and. k <= grid%nz_local) then
      work%run_next(r) = work%row_head(j, k)
      work%row_head(j, k) = r
    end if
  end subroutine add_run

  !> Twice the room for runs, the recorded ones kept.
  subroutine grow_runs(work)
    type(classification_work_t), intent(inout) :: work
    integer :: room
    room = max(1024, 2 * size(work%run_body))
    call resize(work%run_body)
    call resize(work%run_j)
    call resize(work%run_k)
    call resize(work%run_first)
    call resize(work%run_last)
    call resize(work%run_next)
  contains
    subroutine resize(values)
      integer, allocatable, intent(inout) :: values(:)
      integer, allocatable :: kept(:)
      allocate(kept(room))
      kept(1:work%n_runs) = values(1:work%n_runs)
      call move_alloc(kept, values)
    end subroutine resize
  end subroutine grow_runs

end module immersed_geometry
