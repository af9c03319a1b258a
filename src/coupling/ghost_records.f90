!> The record of one ghost node of the immersed boundary (ghost_node_t, immersed_nodes): its closest
!> surface point, normal, image point (with the fallback and saturation near another body) and the
!> trilinear interpolation stencil of the image point on the component's own grid, built for each
!> ghost node the classification (immersed_geometry) finds (docs/theory.md, "Immersed boundary
!> geometry").
!>
!> - Ghost node G, closest surface point B, outward normal n, d_G = |G - B|: image point
!>   M = B + d_M n, with d_M = d_G (the pure mirror, M = 2B - G: the exterior point of the paper's
!>   Eq. 7, u_G = 2 u_IB - u_E, after Mark & van Wachem 2008) or d_M = max(d_G, image_distance_cells
!>   h_max) (the image point of the explicit coupling).
!>   The ghost condition is u_G = u_B - kappa (u_M - u_B), kappa = d_G/d_M.
!> - If the segment from B to M enters another body (a gap below about two cells), M is moved back
!>   along n to the middle of the gap, d_M = s/2 with s the distance from B to the other body
!>   along n, and kappa = d_G/d_M (linear extrapolation); such nodes are flagged and counted. If B
!>   itself lies inside another body (overlapping bodies), M = B and kappa = 0: the ghost takes the
!>   surface velocity.
!> - Below the saturation gap s_min (saturation_gap_cells h_max) the grid resolves nothing of the
!>   film, and kappa = d_G/(s/2) would grow without bound: the row then leaves the fluid out
!>   (kappa = 0) and takes the Couette profile between B and the other body's surface point
!>   B' = B + s n, saturated at s_min: u_G = u_B - c (u_B' - u_B), c = d_G/max(s, s_min), with
!>   u_B' the other body's rigid velocity at B' (the couette_gain, opposite_body and opposite_point
!>   of the record; flagged `saturated` and counted as well as fallback).
!> - u_M = sum_c w_c u_c over the 8 nodes of the component's grid cell that contains M (trilinear);
!>   they may include ghost nodes, interior nodes and G itself, whose weight the implicit ghost
!>   row moves to the diagonal: (1 + kappa w_G) u_G = (1 + kappa) u_B - kappa sum_{c /= G} w_c u_c.
module ghost_records
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp
  use periodic_box, only: minimum_image
  use fluid_grid, only: fluid_grid_t
  use quaternion, only: rotate_to_body
  use spheroid_distance, only: surface_projection_t, lab_closest_point
  use mesh_distance, only: mesh_lab_closest_point
  use immersed_nodes, only: immersed_body_t, immersed_options_t, ghost_node_t, node_position, wrap, node_ghost
  implicit none
  private
  public :: build_ghost_record

contains

  !> Closest point, normal, image point (with the other-body fallback) and trilinear stencil of
  !> one ghost node. status covers (1:nx, 1:ny, k_lo:) in extended local k.
  subroutine build_ghost_record(grid, bodies, options, component, status, k_lo, ghost_index, others, ghost)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    type(immersed_options_t), intent(in) :: options
    integer, intent(in) :: component, k_lo
    integer(int8), intent(in) :: status(:, :, k_lo:)
    integer, intent(in) :: ghost_index(:, :, :)  !< (nx, ny, nz_local) index of each local ghost node, else 0
    integer, intent(in) :: others(:)             !< the bodies the fallback test tries (fallback_candidates)
    type(ghost_node_t), intent(inout) :: ghost
    type(surface_projection_t) :: projection
    real(wp) :: box(3), spacing(3), centre(3), nearest_entry, entry, saturation_gap, fraction(3), t(3), w(0:1, 3)
    integer :: n, m, corner, bits(3), node(3), d, nearest_body

    box = [grid%lx, grid%ly, grid%lz]
    spacing = [grid%dx, grid%dy, grid%dz]
    ghost%position = node_position(grid, component, ghost%node(1), ghost%node(2), ghost%node(3))
    associate (body => bodies(ghost%body))
      ! The image of the body's centre nearest to G: everything below is in G's image frame.
      centre = ghost%position - minimum_image(ghost%position - body%centre, box)
      if (body%mesh%level >= 0) then
        projection = mesh_lab_closest_point(body%mesh, centre, body%orientation, ghost%position)
      else
        projection = lab_closest_point(body%shape, centre, body%orientation, ghost%position)
      end if
    end associate
    ghost%surface_point = projection%point
    ghost%normal = projection%normal
    ! |d|: G is inside by the implicit function; the computed distance can only be off by round-off.
    ghost%distance = abs(projection%signed_distance)
    if (trim(options%image_point) == 'image') then
      ghost%image_distance = max(ghost%distance, options%image_distance_cells * maxval(spacing))
    else
      ghost%image_distance = ghost%distance
    end if

    ! Fallback: the segment B -> B + d_M n must not enter another body; if it does, M goes to the
    ! middle of the gap to the nearest body along n.
    nearest_entry = huge(1.0_wp)
    nearest_body = 0
    do m = 1, size(others)
      n = others(m)
      entry = segment_entry(bodies(n), box, ghost%surface_point, ghost%normal, ghost%image_distance)
      if (entry < nearest_entry) then
        nearest_entry = entry
        nearest_body = n
      end if
    end do
    ghost%fallback = nearest_entry < ghost%image_distance
    if (ghost%fallback) ghost%image_distance = 0.5_wp * nearest_entry
    ghost%image_point = ghost%surface_point + ghost%image_distance * ghost%normal
    if (ghost%image_distance > 0.0_wp) then
      ghost%extrapolation = ghost%distance / ghost%image_distance
    else
      ghost%extrapolation = 0.0_wp
    end if
    ! Saturation: below s_min the midpoint row's gain 2 d_G/s would feed the fluid next to the gap
    ! back into the explicit Laplacian without bound; the row takes the Couette profile of the two
    ! surfaces instead (no fluid node; equal to the midpoint row for a linear gap profile at s_min).
    ! An overlap (s = 0) keeps u_G = u_B.
    saturation_gap = options%saturation_gap_cells * maxval(spacing)
    ghost%saturated = ghost%fallback .and. nearest_entry > 0.0_wp .and. nearest_entry < saturation_gap
    if (ghost%saturated) then
      ghost%opposite_body = nearest_body
      ghost%opposite_point = ghost%surface_point + nearest_entry * ghost%normal
      ghost%couette_gain = ghost%distance / saturation_gap
      ghost%extrapolation = 0.0_wp
    else
      ghost%opposite_body = 0
      ghost%opposite_point = 0.0_wp
      ghost%couette_gain = 0.0_wp
    end if

    ! Trilinear stencil of M, located relative to G in index space (no wrap of positions needed).
    fraction = real(ghost%node, wp) + (ghost%image_point - ghost%position) / spacing
    ghost%lower_offset = floor(fraction) - ghost%node
    t = fraction - floor(fraction)
    do d = 1, 3
      w(0, d) = 1.0_wp - t(d)
      w(1, d) = t(d)
    end do
    ghost%self_corner = 0
    do corner = 1, 8
      bits = [mod(corner - 1, 2), mod((corner - 1) / 2, 2), (corner - 1) / 4]
      node = ghost%node + ghost%lower_offset + bits     ! i, j unwrapped; k local, extended
      ghost%weight(corner) = w(bits(1), 1) * w(bits(2), 2) * w(bits(3), 3)
      ghost%stencil(:, corner) = [wrap(node(1), grid%nx), wrap(node(2), grid%ny), &
                                  wrap(grid%z_offset + node(3), grid%nz)]
      ghost%stencil_status(corner) = status(ghost%stencil(1, corner), ghost%stencil(2, corner), node(3))
      ghost%stencil_local(corner) = node(3) >= 1 .and. node(3) <= grid%nz_local
      ghost%stencil_ghost(corner) = 0
      if (ghost%stencil_local(corner) .and. ghost%stencil_status(corner) == node_ghost) &
        ghost%stencil_ghost(corner) = ghost_index(ghost%stencil(1, corner), ghost%stencil(2, corner), node(3))
      if (all(bits + ghost%lower_offset == 0)) ghost%self_corner = corner
    end do
  end subroutine build_ghost_record

  !> Distance s in [0, length] along the ray b + s n at which it first enters `body` (the periodic
  !> image nearest b), or huge if it does not within length. 0 if b is inside the body.
  function segment_entry(body, box, b, n, length) result(entry)
    type(immersed_body_t), intent(in) :: body
    real(wp), intent(in) :: box(3), b(3), n(3), length
    real(wp) :: entry, y0(3), m(3), inverse_squares(3), qa, qb, qc, discriminant, root
    entry = huge(1.0_wp)
    ! Quick rejection: the segment cannot reach the body's bounding sphere.
    y0 = minimum_image(b - body%centre, box)
    if (norm2(y0) > max(body%shape%a, body%shape%b) + length) return
    y0 = rotate_to_body(body%orientation, y0)
    m = rotate_to_body(body%orientation, n)
    inverse_squares = [1.0_wp / body%shape%a**2, 1.0_wp / body%shape%b**2, 1.0_wp / body%shape%b**2]
    ! F(y0 + s m) = qa s^2 + 2 qb s + qc (implicit function along the ray).
    qa = sum(inverse_squares * m**2)
    qb = sum(inverse_squares * y0 * m)
    qc = sum(inverse_squares * y0**2) - 1.0_wp
    if (qc < 0.0_wp) then
      entry = 0.0_wp
      return
    end if
    discriminant = qb**2 - qa * qc
    if (discriminant < 0.0_wp .or. qb >= 0.0_wp) return    ! misses, or moves away (qc >= 0)
    ! Smaller root of qa s^2 + 2 qb s + qc with qb < 0, in the cancellation-free form.
    root = qc / (-qb + sqrt(discriminant))
    if (root <= length) entry = root
  end function segment_entry

end module ghost_records
