!> Values and gradients of grid fields at arbitrary points of the periodic box: any staggered
!> velocity component (on its own MAC nodes) and the pressure (cell centres). What the immersed
!> boundary's loads and the point-particle coupling read from the fluid.
!>
!> Value: trilinear interpolation between the 2 x 2 x 2 nodes of the field's own grid around the
!> point (exact for trilinear fields, second order for smooth ones).
!> Gradient: d f / d x_d is the centred difference of neighbouring nodes along d, which sits
!> half-way between them (second order there), interpolated trilinearly to the point; so the
!> gradient is exact for trilinear fields and second order for smooth ones.
!>
!> Parallel layout (docs/design.md, "Interpolation at points"): a point is evaluated by the rank
!> whose slab holds its z (after wrapping it into the box), from that rank's field with its one
!> halo layer; the collective routines then sum over ranks. One layer is enough: along x and y
!> every rank holds the whole periodic plane (indices wrap), and along z the nodes around any
!> point of the slab lie on the slab or on its halo planes. The one exception is d/dz of a field
!> on the z faces (w): its stencil reaches from the face below z - dz/2 to two faces above, so it
!> is evaluated by the rank whose slab holds z - dz/2 (derivative_on_this_rank), which holds all
!> three faces with its halo. Every value and derivative is thus computed from the same global
!> nodes with the same weights on any number of ranks: results agree to round-off (bit for bit
!> but for the order of the final sum). Fields must have current halos.
module field_interpolation
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  use error_handling, only: fatal
  use fluid_grid, only: fluid_grid_t
  implicit none
  private
  public :: on_x_faces, on_y_faces, on_z_faces, on_cell_centres, point_on_this_rank, interpolate_here, &
            interpolate_at_points, gradient_at_points, velocity_gradient_at_points, velocity_and_gradient_at_points, &
            sampling_order

  !> Where a field's nodes are (fluid_grid): u on the x faces, v on y, w on z, pressure at centres.
  integer, parameter :: on_x_faces = 1, on_y_faces = 2, on_z_faces = 3, on_cell_centres = 4

contains

  !> True if the point (m, any position: it is wrapped into the box) is evaluated on this rank.
  logical function point_on_this_rank(grid, point)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: point(3)
    point_on_this_rank = slab_holds(grid, point(3))
  end function point_on_this_rank

  !> True if this rank evaluates d/dx_derivative of a field at the point: the rank of the point,
  !> except for d/dz on the z faces, the rank of z - dz/2 (see the module header).
  logical function derivative_on_this_rank(grid, point, location, derivative)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: point(3)
    integer, intent(in) :: location, derivative
    if (location == on_z_faces .and. derivative == 3) then
      derivative_on_this_rank = slab_holds(grid, point(3) - 0.5_wp * grid%dz)
    else
      derivative_on_this_rank = slab_holds(grid, point(3))
    end if
  end function derivative_on_this_rank

  !> True if this rank's slab holds the cell of height z (any value: wrapped into the box).
  logical function slab_holds(grid, z)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: z
    integer :: cell
    ! min: z just below lz may divide to nz by rounding; it belongs to the top cell.
    cell = min(floor(wrapped(z, grid%lz) / grid%dz), grid%nz - 1)
    slab_holds = (cell >= grid%z_offset .and. cell < grid%z_offset + grid%nz_local)
  end function slab_holds

  !> The field's value at a point this rank evaluates (point_on_this_rank).
  real(wp) function interpolate_here(grid, field, location, point) result(value)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: location
    real(wp), intent(in) :: point(3)
    value = stencil_sum(grid, field, location, point, 0)
  end function interpolate_here

  !> values(p) = field at points(:, p) on every rank (collective; every rank passes the same points).
  !> With `mask` (0 or 1 per node of the field, same layout and halos), only the nodes of mask 1
  !> count, the trilinear weights renormalised over them (e.g. the pressure at a probe near an
  !> immersed body without the cells inside it; unmasked where no weight remains).
  subroutine interpolate_at_points(grid, field, location, points, values, mask)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: location
    real(wp), intent(in) :: points(:, :)          !< (3, n), m
    real(wp), intent(out) :: values(:)            !< (n)
    real(wp), intent(in), optional :: mask(0:, 0:, 0:)
    real(wp) :: kept
    integer :: p
    values = 0
    do p = 1, size(points, 2)
      if (.not. point_on_this_rank(grid, points(:, p))) cycle
      values(p) = interpolate_here(grid, field, location, points(:, p))
      if (.not. present(mask)) cycle
      kept = interpolate_here(grid, mask, location, points(:, p))
      if (kept > 1.0e-12_wp) values(p) = stencil_sum(grid, field, location, points(:, p), 0, mask) / kept
    end do
    call MPI_Allreduce(MPI_IN_PLACE, values, size(values), mpi_wp, MPI_SUM, world)
  end subroutine interpolate_at_points

  !> gradients(:, p) = grad field at points(:, p) on every rank (collective).
  subroutine gradient_at_points(grid, field, location, points, gradients)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: location
    real(wp), intent(in) :: points(:, :)          !< (3, n), m
    real(wp), intent(out) :: gradients(:, :)      !< (3, n), field unit per m
    integer :: p
    integer :: d
    gradients = 0
    do p = 1, size(points, 2)
      do d = 1, 3
        if (derivative_on_this_rank(grid, points(:, p), location, d)) &
            gradients(d, p) = stencil_sum(grid, field, location, points(:, p), d)
      end do
    end do
    call MPI_Allreduce(MPI_IN_PLACE, gradients, size(gradients), mpi_wp, MPI_SUM, world)
  end subroutine gradient_at_points

  !> gradients(a, b, p) = d u_a / d x_b at points(:, p) (1/s) on every rank (collective); u, v, w
  !> the staggered velocity with current halos.
  subroutine velocity_gradient_at_points(grid, u, v, w, points, gradients)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: points(:, :)          !< (3, n), m
    real(wp), intent(out) :: gradients(:, :, :)   !< (3, 3, n)
    integer :: p, d
    gradients = 0
    do p = 1, size(points, 2)
      do d = 1, 3
        if (derivative_on_this_rank(grid, points(:, p), on_x_faces, d)) &
            gradients(1, d, p) = stencil_sum(grid, u, on_x_faces, points(:, p), d)
        if (derivative_on_this_rank(grid, points(:, p), on_y_faces, d)) &
            gradients(2, d, p) = stencil_sum(grid, v, on_y_faces, points(:, p), d)
        if (derivative_on_this_rank(grid, points(:, p), on_z_faces, d)) &
            gradients(3, d, p) = stencil_sum(grid, w, on_z_faces, points(:, p), d)
      end do
    end do
    call MPI_Allreduce(MPI_IN_PLACE, gradients, size(gradients), mpi_wp, MPI_SUM, world)
  end subroutine velocity_gradient_at_points

  !> interpolate_at_points of u, v and w and velocity_gradient_at_points in one pass over the
  !> points (collective): each point's 12 values from the axis stencils it shares (the value's
  !> stencils along the axes a derivative does not act on), every value the same arithmetic and
  !> the same rank as in those two routines. One pass keeps each point's nodes in cache. visit:
  !> the points this rank evaluates, in the order to visit them (sampling_order; every rank passes
  !> its own); without it every point in the given order, those of other ranks skipped. The
  !> visited points are copied into that order first and their values copied back after: loops
  !> that only move data overlap their cache misses, the stencil sums would wait on each.
  subroutine velocity_and_gradient_at_points(grid, u, v, w, points, velocity, gradients, visit)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: points(:, :)          !< (3, n), m
    real(wp), intent(out) :: velocity(:, :)       !< (3, n)
    real(wp), intent(out) :: gradients(:, :, :)   !< (3, 3, n)
    integer, intent(in), optional :: visit(:)
    real(wp), allocatable :: visited_velocity(:, :), visited_gradients(:, :, :)
    if (present(visit)) then
      allocate(visited_velocity(3, size(visit)), visited_gradients(3, 3, size(visit)))
      call sample_in_order(grid, u, v, w, points(:, visit), visited_velocity, visited_gradients)
      velocity = 0
      gradients = 0
      velocity(:, visit) = visited_velocity
      gradients(:, :, visit) = visited_gradients
    else
      call sample_in_order(grid, u, v, w, points, velocity, gradients)
    end if
    call MPI_Allreduce(MPI_IN_PLACE, velocity, size(velocity), mpi_wp, MPI_SUM, world)
    call MPI_Allreduce(MPI_IN_PLACE, gradients, size(gradients), mpi_wp, MPI_SUM, world)
  end subroutine velocity_and_gradient_at_points

  !> This rank's part of velocity_and_gradient_at_points at the points, in their order (zero for
  !> what another rank evaluates; no communication).
  subroutine sample_in_order(grid, u, v, w, points, velocity, gradients)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: points(:, :)
    real(wp), intent(out) :: velocity(:, :), gradients(:, :, :)
    real(wp) :: q(3)
    logical :: here, below
    integer :: p
    velocity = 0
    gradients = 0
    do p = 1, size(points, 2)
      here = point_on_this_rank(grid, points(:, p))
      below = derivative_on_this_rank(grid, points(:, p), on_z_faces, 3)
      if (.not. (here .or. below)) cycle   ! another rank's point: nothing of it here
      q = [wrapped(points(1, p), grid%lx), wrapped(points(2, p), grid%ly), wrapped(points(3, p), grid%lz)]
      call component(u, on_x_faces, 1)
      call component(v, on_y_faces, 2)
      call component(w, on_z_faces, 3)
    end do
  contains
    !> Component k (on location's nodes) at point p: its value and its three derivatives.
    subroutine component(field, location, k)
      real(wp), intent(in) :: field(0:, 0:, 0:)
      integer, intent(in) :: location, k
      integer :: ix(3), iy(3), iz(3), jx(3), jy(3), jz(3)
      real(wp) :: wx(3), wy(3), wz(3), dx(3), dy(3), dz(3)
      logical :: z_here
      call axis_stencil(q(1), grid%dx, grid%nx, location /= on_x_faces, .false., .false., 0, 0, ix, wx)
      call axis_stencil(q(2), grid%dy, grid%ny, location /= on_y_faces, .false., .false., 0, 0, iy, wy)
      if (here) then
        call axis_stencil(q(3), grid%dz, grid%nz, location /= on_z_faces, .false., .true., grid%z_offset, &
                          grid%nz_local, iz, wz)
        velocity(k, p) = weighted_sum(field, ix, wx, iy, wy, iz, wz)
        call axis_stencil(q(1), grid%dx, grid%nx, location /= on_x_faces, .true., .false., 0, 0, jx, dx)
        gradients(k, 1, p) = weighted_sum(field, jx, dx, iy, wy, iz, wz)
        call axis_stencil(q(2), grid%dy, grid%ny, location /= on_y_faces, .true., .false., 0, 0, jy, dy)
        gradients(k, 2, p) = weighted_sum(field, ix, wx, jy, dy, iz, wz)
      end if
      z_here = here
      if (location == on_z_faces) z_here = below
      if (.not. z_here) return
      call axis_stencil(q(3), grid%dz, grid%nz, location /= on_z_faces, .true., .true., grid%z_offset, &
                        grid%nz_local, jz, dz)
      gradients(k, 3, p) = weighted_sum(field, ix, wx, iy, wy, jz, dz)
    end subroutine component
  end subroutine sample_in_order

  !> visit: the points (3, n) this rank evaluates anything of in velocity_and_gradient_at_points
  !> (its own, and those whose d/dz of w it evaluates), ordered by the grid cell that holds them: z
  !> plane, y row, then x (two stable counting sorts, O(n + nx + ny nz)). Consecutive points then
  !> share most of their stencils' cache lines; the order changes no value, only the memory traffic.
  subroutine sampling_order(grid, points, visit)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: points(:, :)
    integer, allocatable, intent(out) :: visit(:)
    integer, allocatable :: mine(:), by_x(:), key(:)
    integer :: p, m, count
    allocate(mine(size(points, 2)))
    count = 0
    do p = 1, size(points, 2)
      if (.not. (point_on_this_rank(grid, points(:, p)) .or. &
                 derivative_on_this_rank(grid, points(:, p), on_z_faces, 3))) cycle
      count = count + 1
      mine(count) = p
    end do
    allocate(key(count), by_x(count), visit(count))
    do m = 1, count
      key(m) = cell_of(points(1, mine(m)), grid%lx, grid%dx, grid%nx)
    end do
    call counting_sort(key, grid%nx, mine(1:count), by_x)
    do m = 1, count
      p = by_x(m)
      key(m) = cell_of(points(2, p), grid%ly, grid%dy, grid%ny) + grid%ny * cell_of(points(3, p), grid%lz, grid%dz, grid%nz)
    end do
    call counting_sort(key, grid%ny * grid%nz, by_x, visit)
  contains
    !> 0-based cell of coordinate x along an axis of n cells of width h over the period length.
    integer function cell_of(x, length, h, n)
      real(wp), intent(in) :: x, length, h
      integer, intent(in) :: n
      cell_of = min(n - 1, max(0, floor(wrapped(x, length) / h)))
    end function cell_of
    !> sorted = items stably ordered by key (0..buckets - 1).
    subroutine counting_sort(key, buckets, items, sorted)
      integer, intent(in) :: key(:), buckets, items(:)
      integer, intent(out) :: sorted(:)
      integer :: first(0:buckets), k
      first = 0
      do k = 1, size(key)
        first(key(k) + 1) = first(key(k) + 1) + 1
      end do
      first(0) = 1
      do k = 1, buckets
        first(k) = first(k) + first(k - 1)
      end do
      do k = 1, size(key)
        sorted(first(key(k))) = items(k)
        first(key(k)) = first(key(k)) + 1
      end do
    end subroutine counting_sort
  end subroutine sampling_order

  !> x wrapped into [0, length) (modulo alone can round up to length itself for tiny negative x).
  pure real(wp) function wrapped(x, length)
    real(wp), intent(in) :: x, length
    wrapped = modulo(x, length)
    if (wrapped >= length) wrapped = 0
  end function wrapped

  !> Sum over the point's stencil: the value (derivative = 0) or d/dx_derivative. Each direction
  !> contributes up to 3 nodes (weights in axis_stencil); z indices are local to the slab.
  !> With `factor`, each node's value is multiplied by the factor's value at the node.
  real(wp) function stencil_sum(grid, field, location, point, derivative, factor) result(total)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: location, derivative
    real(wp), intent(in) :: point(3)
    real(wp), intent(in), optional :: factor(0:, 0:, 0:)
    integer :: ix(3), iy(3), iz(3), a, b, c
    real(wp) :: wx(3), wy(3), wz(3)
    if (location < on_x_faces .or. location > on_cell_centres) call fatal('field_interpolation: unknown location')
    call axis_stencil(wrapped(point(1), grid%lx), grid%dx, grid%nx, location /= on_x_faces, derivative == 1, .false., &
                      0, 0, ix, wx)
    call axis_stencil(wrapped(point(2), grid%ly), grid%dy, grid%ny, location /= on_y_faces, derivative == 2, .false., &
                      0, 0, iy, wy)
    call axis_stencil(wrapped(point(3), grid%lz), grid%dz, grid%nz, location /= on_z_faces, derivative == 3, .true., &
                      grid%z_offset, grid%nz_local, iz, wz)
    if (.not. present(factor)) then
      total = weighted_sum(field, ix, wx, iy, wy, iz, wz)
      return
    end if
    total = 0
    do c = 1, 3
      if (wz(c) == 0.0_wp) cycle   ! an exact zero weight (unused third node): skip its loads
      do b = 1, 3
        if (wy(b) == 0.0_wp) cycle
        do a = 1, 3
          total = total + wx(a) * wy(b) * wz(c) * field(ix(a), iy(b), iz(c)) * factor(ix(a), iy(b), iz(c))
        end do
      end do
    end do
  end function stencil_sum

  !> The sum of the field's nodes (ix, iy, iz) with the weights (wx, wy, wz) of axis_stencil.
  pure real(wp) function weighted_sum(field, ix, wx, iy, wy, iz, wz) result(total)
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: ix(3), iy(3), iz(3)
    real(wp), intent(in) :: wx(3), wy(3), wz(3)
    integer :: a, b, c, last_x
    ! An exact zero weight (a value stencil's unused third node) adds nothing: skip its loads.
    last_x = 3
    if (wx(3) == 0.0_wp) last_x = 2
    total = 0
    do c = 1, 3
      if (wz(c) == 0.0_wp) cycle
      do b = 1, 3
        if (wy(b) == 0.0_wp) cycle
        do a = 1, last_x
          total = total + wx(a) * wy(b) * wz(c) * field(ix(a), iy(b), iz(c))
        end do
      end do
    end do
  end function weighted_sum

  !> Nodes and weights along one direction for coordinate s in [0, n h). Node m (global, 1-based)
  !> is at (m - 1/2) h for a centred direction, m h for a face direction. Value: the two nodes
  !> around s, linear weights. Derivative: the differences D_m = (f_{m+1} - f_m) / h sit half-way,
  !> the two around s are combined linearly, giving three nodes. Periodic directions wrap the
  !> index into 1..n; the slab direction (sliced) returns local indices 0..nz_local+1 on the rank
  !> that evaluates the point (point_on_this_rank, derivative_on_this_rank): there the first node
  !> is on the slab, once a stencil that starts below the box (d/dz on the z faces for
  !> s < h/2, evaluated by the top slab) is moved up by the period.
  subroutine axis_stencil(s, h, n, centred, derivative, sliced, offset, n_local, index, weight)
    real(wp), intent(in) :: s, h
    integer, intent(in) :: n, offset, n_local
    logical, intent(in) :: centred, derivative, sliced
    integer, intent(out) :: index(3)
    real(wp), intent(out) :: weight(3)
    real(wp) :: q, t
    integer :: m0, j
    q = s / h
    if (centred) q = q + 0.5_wp
    if (derivative) q = q - 0.5_wp
    m0 = floor(q)
    t = q - m0
    if (sliced .and. m0 < offset) m0 = m0 + n
    if (derivative) then
      weight = [-(1.0_wp - t), 1.0_wp - 2.0_wp * t, t] / h
    else
      weight = [1.0_wp - t, t, 0.0_wp]
    end if
    do j = 1, 3
      if (sliced) then
        index(j) = m0 + j - 1 - offset
      else
        ! modulo(m0 + j - 2, n) + 1 for m0 + j - 2 in [-n, 2n) (s in [0, L): m0 in [-1, n]),
        ! without an integer division (the inner loop of every point sample).
        index(j) = m0 + j - 2
        if (index(j) < 0) then
          index(j) = index(j) + n
        else if (index(j) >= n) then
          index(j) = index(j) - n
        end if
        if (index(j) < 0 .or. index(j) >= n) index(j) = modulo(m0 + j - 2, n)
        index(j) = index(j) + 1
      end if
    end do
    if (sliced) then
      if (.not. derivative) index(3) = index(2)   ! weight 0: any valid index
      if (index(1) < 0 .or. index(3) > n_local + 1) &
          call fatal('field_interpolation: point outside the slab of this rank (use point_on_this_rank)', &
                     collective=.false.)
    end if
  end subroutine axis_stencil
end module field_interpolation
