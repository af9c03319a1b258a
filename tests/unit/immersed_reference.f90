!> Independent reference for the immersed-geometry tests: the status of any node of any velocity
!> component by brute force (own node-position formula from the MAC layout of fluid_grid.f90's
!> header, own inside test x^2/a^2 + (y^2 + z^2)/b^2 < 1 at the periodic minimum image, global
!> indices, all bodies, no bounding boxes), and checks of every ghost record against it and against
!> the closest-point geometry.
module immersed_reference
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp
  use quaternion, only: rotation_matrix
  use fluid_grid, only: fluid_grid_t
  use spheroid_distance, only: surface_projection_t, lab_closest_point
  use immersed_geometry, only: immersed_body_t, immersed_geometry_t, ghost_node_t, node_fluid, node_ghost, &
                               node_interior
  implicit none
  private
  public :: record_errors_t, reference_position, reference_solid, reference_status, check_geometry_against_reference

  !> Worst deviations found by check_geometry_against_reference (lengths in cells).
  type :: record_errors_t
    integer :: status_mismatches = 0       !< nodes (status arrays incl. halo ring, and stencil flags)
    integer :: list_mismatches = 0         !< ghost/interior lists vs status, stencil_ghost/self links
    !> ghost without a fluid 6-neighbour, interior with one, fluid with an interior 6-neighbour
    integer :: neighbour_violations = 0
    real(wp) :: ghost_distance = 0.0_wp    !< | |G - B| - d_G |, |G - (B - d_G n)|
    real(wp) :: image_distance = 0.0_wp    !< |signed distance of M from its body - d_M|, |M - (B + d_M n)|
    real(wp) :: mirror = 0.0_wp            !< |M - (2B - G)| for pure-mirror records without fallback
    real(wp) :: weight_sum = 0.0_wp        !< |sum w - 1|, and -min(w)
    real(wp) :: linear_field = 0.0_wp      !< |sum w f(x_c) - f(M)| / (|grad f| h), f linear
    real(wp) :: min_outside = huge(1.0_wp) !< smallest signed distance of M from any body (>= 0 expected)
    integer :: ghosts_in_stencils = 0      !< stencil corners that are ghost nodes (weight > 0)
    integer :: self_in_stencils = 0        !< records with G in its own stencil (weight > 0)
  end type record_errors_t

contains

  !> Position of node (i, j, k) (global indices, any integers) of component c: the face
  !> coordinate i h along c, the centre coordinate (i - 1/2) h across.
  pure function reference_position(grid, c, i, j, k) result(x)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: c, i, j, k
    real(wp) :: x(3), shift(3)
    shift = 0.5_wp
    shift(c) = 0.0_wp
    x = ([real(i, wp), real(j, wp), real(k, wp)] - shift) * [grid%dx, grid%dy, grid%dz]
  end function reference_position

  pure logical function reference_solid(grid, bodies, c, i, j, k)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    integer, intent(in) :: c, i, j, k
    real(wp) :: x(3), d(3), y(3), box(3)
    integer :: n
    box = [grid%lx, grid%ly, grid%lz]
    x = reference_position(grid, c, i, j, k)
    reference_solid = .false.
    do n = 1, size(bodies)
      d = x - bodies(n)%centre
      d = d - box * anint(d / box)
      y = matmul(transpose(rotation_matrix(bodies(n)%orientation)), d)
      if (y(1)**2 / bodies(n)%shape%a**2 + (y(2)**2 + y(3)**2) / bodies(n)%shape%b**2 < 1.0_wp) &
        reference_solid = .true.
    end do
  end function reference_solid

  !> node_fluid, node_ghost (solid with a fluid 6-neighbour) or node_interior; global indices,
  !> wrapped periodically.
  pure integer(int8) function reference_status(grid, bodies, c, i, j, k)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    integer, intent(in) :: c, i, j, k
    integer :: ii, jj, kk
    ii = modulo(i - 1, grid%nx) + 1
    jj = modulo(j - 1, grid%ny) + 1
    kk = modulo(k - 1, grid%nz) + 1
    if (.not. reference_solid(grid, bodies, c, ii, jj, kk)) then
      reference_status = node_fluid
    else if (.not. (reference_solid(grid, bodies, c, ii - 1, jj, kk) .and. reference_solid(grid, bodies, c, ii + 1, jj, kk) &
             .and. reference_solid(grid, bodies, c, ii, jj - 1, kk) .and. reference_solid(grid, bodies, c, ii, jj + 1, kk) &
             .and. reference_solid(grid, bodies, c, ii, jj, kk - 1) .and. reference_solid(grid, bodies, c, ii, jj, kk + 1))) then
      reference_status = node_ghost
    else
      reference_status = node_interior
    end if
  end function reference_status

  !> Compare this rank's classification with the reference node by node (the status arrays with
  !> their halo ring), the ghost and interior lists with the status, and every ghost record with
  !> the geometry: errors accumulate into `errors` (call with a fresh record_errors_t to reset).
  subroutine check_geometry_against_reference(grid, bodies, mirror, geometry, errors)
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    logical, intent(in) :: mirror        !< pure-mirror options (d_M = d_G)
    type(immersed_geometry_t), intent(in) :: geometry
    type(record_errors_t), intent(inout) :: errors
    integer :: c, i, j, k, g, corner, n, bits(3), node(3)
    real(wp) :: h(3), box(3), gradient(3), centre(3), interpolated, x(3)
    type(ghost_node_t) :: r
    integer(int8) :: neighbours(6)
    type(surface_projection_t) :: p

    h = [grid%dx, grid%dy, grid%dz]
    box = [grid%lx, grid%ly, grid%lz]
    gradient = [0.3_wp, -1.1_wp, 0.7_wp]
    do c = 1, 3
      associate (nodes => geometry%component(c))
        do k = 0, grid%nz_local + 1
          do j = 0, grid%ny + 1
            do i = 0, grid%nx + 1
              if (nodes%status(i, j, k) /= reference_status(grid, bodies, c, i, j, grid%z_offset + k)) &
                errors%status_mismatches = errors%status_mismatches + 1
            end do
          end do
        end do
        ! The 6-neighbour invariants, on this rank's nodes (the halo ring holds their neighbours).
        do k = 1, grid%nz_local
          do j = 1, grid%ny
            do i = 1, grid%nx
              neighbours = [nodes%status(i - 1, j, k), nodes%status(i + 1, j, k), nodes%status(i, j - 1, k), &
                            nodes%status(i, j + 1, k), nodes%status(i, j, k - 1), nodes%status(i, j, k + 1)]
              select case (nodes%status(i, j, k))
              case (node_ghost)
                if (.not. any(neighbours == node_fluid)) errors%neighbour_violations = errors%neighbour_violations + 1
              case (node_interior)
                if (any(neighbours == node_fluid)) errors%neighbour_violations = errors%neighbour_violations + 1
              case (node_fluid)
                if (any(neighbours == node_interior)) errors%neighbour_violations = errors%neighbour_violations + 1
              end select
            end do
          end do
        end do
        if (nodes%n_ghost /= count(nodes%status(1:grid%nx, 1:grid%ny, 1:grid%nz_local) == node_ghost) .or. &
            nodes%n_interior /= count(nodes%status(1:grid%nx, 1:grid%ny, 1:grid%nz_local) == node_interior)) &
          errors%list_mismatches = errors%list_mismatches + 1
        do g = 1, nodes%n_interior
          if (nodes%status(nodes%interior(1, g), nodes%interior(2, g), nodes%interior(3, g)) /= node_interior) &
            errors%list_mismatches = errors%list_mismatches + 1
        end do
        do g = 1, nodes%n_ghost
          r = nodes%ghost(g)
          if (nodes%status(r%node(1), r%node(2), r%node(3)) /= node_ghost) errors%list_mismatches = errors%list_mismatches + 1
          x = reference_position(grid, c, r%node(1), r%node(2), grid%z_offset + r%node(3))
          errors%ghost_distance = max(errors%ghost_distance, maxval(abs(r%position - x) / h), &
                                      abs(norm2(r%position - r%surface_point) - r%distance) / h(1), &
                                      maxval(abs(r%position - (r%surface_point - r%distance * r%normal)) / h))
          errors%image_distance = max(errors%image_distance, &
                                      maxval(abs(r%image_point - (r%surface_point + r%image_distance * r%normal)) / h))
          if (mirror .and. .not. r%fallback) errors%mirror = max(errors%mirror, &
                                      maxval(abs(r%image_point - (2.0_wp * r%surface_point - r%position)) / h))
          ! M is outside every body; at distance d_M from its own body.
          do n = 1, size(bodies)
            centre = r%image_point - (r%image_point - bodies(n)%centre - box * anint((r%image_point - bodies(n)%centre) / box))
            p = lab_closest_point(bodies(n)%shape, centre, bodies(n)%orientation, r%image_point)
            if (n == r%body) errors%image_distance = max(errors%image_distance, &
                                                         abs(p%signed_distance - r%image_distance) / h(1))
            if (n /= r%body .or. r%image_distance > 0.0_wp) errors%min_outside = min(errors%min_outside, p%signed_distance)
          end do
          ! Weights and stencil.
          errors%weight_sum = max(errors%weight_sum, abs(sum(r%weight) - 1.0_wp), -minval(r%weight))
          interpolated = 0.0_wp
          do corner = 1, 8
            bits = [mod(corner - 1, 2), mod((corner - 1) / 2, 2), (corner - 1) / 4]
            node = r%node + r%lower_offset + bits
            interpolated = interpolated + r%weight(corner) * dot_product(gradient, &
                reference_position(grid, c, node(1), node(2), grid%z_offset + node(3)))
            if (any(r%stencil(:, corner) /= [modulo(node(1) - 1, grid%nx) + 1, modulo(node(2) - 1, grid%ny) + 1, &
                                              modulo(grid%z_offset + node(3) - 1, grid%nz) + 1])) &
              errors%list_mismatches = errors%list_mismatches + 1
            if (r%stencil_status(corner) /= reference_status(grid, bodies, c, r%stencil(1, corner), &
                                                             r%stencil(2, corner), r%stencil(3, corner))) &
              errors%status_mismatches = errors%status_mismatches + 1
            if (r%stencil_local(corner) .neqv. (node(3) >= 1 .and. node(3) <= grid%nz_local)) &
              errors%list_mismatches = errors%list_mismatches + 1
            if (r%stencil_ghost(corner) > 0) then
              if (any(nodes%ghost(r%stencil_ghost(corner))%node /= &
                      [r%stencil(1, corner), r%stencil(2, corner), node(3)])) errors%list_mismatches = errors%list_mismatches + 1
            else if (r%stencil_local(corner) .and. r%stencil_status(corner) == node_ghost) then
              errors%list_mismatches = errors%list_mismatches + 1
            end if
            if ((corner == r%self_corner) .neqv. all(node == r%node)) errors%list_mismatches = errors%list_mismatches + 1
            if (r%stencil_status(corner) == node_ghost .and. r%weight(corner) > 0.0_wp) &
              errors%ghosts_in_stencils = errors%ghosts_in_stencils + 1
          end do
          if (r%self_corner > 0) then
            if (r%weight(r%self_corner) > 0.0_wp) errors%self_in_stencils = errors%self_in_stencils + 1
          end if
          errors%linear_field = max(errors%linear_field, &
                                    abs(interpolated - dot_product(gradient, r%image_point)) / (norm2(gradient) * h(1)))
        end do
      end associate
    end do
  end subroutine check_geometry_against_reference

end module immersed_reference
