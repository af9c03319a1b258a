! ranks: 2
! checks: 37
!> Interpolation of grid fields to points (field_interpolation) on 2 ranks, for the three
!> staggered velocity grids and the cell centres:
!> - a trilinear field is interpolated exactly, with its exact gradient, at points anywhere in z
!>   (both slabs, next to the rank boundary and the z wrap; trilinear interpolation reproduces
!>   trilinear functions, and centred differences of a trilinear function are exact);
!> - a smooth periodic field at points next to the periodic wrap in x, y, z, on both sides of the
!>   rank boundary, and outside the box (wrapped): the rms errors of value and gradient converge at second order
!>   (16^3, 32^3, 64^3; the design order of trilinear interpolation and centred differences);
!> - the gradient of the smooth field equals the difference of the interpolated values half a node
!>   spacing either side, (f(x + h/2 e_d) - f(x - h/2 e_d)) / h, to round-off: for trilinear
!>   interpolation that is the centred node differences interpolated linearly, the same nodes and
!>   weights whichever rank evaluates them. It checks that no rank extrapolates near its slab's
!>   lower boundary (d/dz of w there needs the rank below): the gradient does not depend on the
!>   number of ranks;
!> - the point coupling's path (velocity_and_gradient_at_points with the visiting order of
!>   sampling_order): each rank's list in the order of the points' grid cells (z plane, y row, x),
!>   every point in some rank's list, and the 12 values per point those of interpolate_at_points
!>   and velocity_gradient_at_points to round-off.
program test_field_interpolation
  use agglo_kinds, only: wp, i8
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use physical_constants, only: two_pi
  use parallel_env, only: parallel_start, is_root
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field, exchange_halos
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_INTEGER, MPI_SUM, MPI_MIN, MPI_COMM_WORLD
  use field_interpolation, only: on_x_faces, on_y_faces, on_z_faces, on_cell_centres, interpolate_at_points, &
                                 gradient_at_points, velocity_gradient_at_points, velocity_and_gradient_at_points, &
                                 sampling_order
  use test_framework, only: test_start, test_finish, check, check_below, check_above
  implicit none
  real(wp), parameter :: lx = 1.0_wp, ly = 0.5_wp, lz = 2.0_wp
  character(len=12), parameter :: names(4) = [character(len=12) :: 'x_faces', 'y_faces', 'z_faces', 'cell_centres']
  real(wp), allocatable :: points(:, :)
  real(wp) :: value_errors(3, 4), gradient_errors(3, 4), velocity_gradient_errors(3)
  integer :: location, n

  call parallel_start()
  call test_start('field_interpolation')
  call make_points()

  do location = 1, 4
    call check_trilinear(location)
  end do

  do location = 1, 4
    call check_half_cell_differences(location)
  end do

  do n = 1, 3
    call smooth_errors(8 * 2**n, value_errors(n, :), gradient_errors(n, :), velocity_gradient_errors(n))
  end do
  do location = 1, 4
    if (is_root()) write(*, '(a,3es11.3,a,3es11.3)') '  '//names(location)//' rms value error 16,32,64:', &
        value_errors(:, location), '  gradient:', gradient_errors(:, location)
    call check_above(order(value_errors(1:2, location)), 1.8_wp, 'smooth_value_order_16_32_'//trim(names(location)))
    call check_above(order(value_errors(2:3, location)), 1.8_wp, 'smooth_value_order_32_64_'//trim(names(location)))
    call check_above(order(gradient_errors(1:2, location)), 1.8_wp, 'smooth_gradient_order_16_32_'//trim(names(location)))
    call check_above(order(gradient_errors(2:3, location)), 1.8_wp, 'smooth_gradient_order_32_64_'//trim(names(location)))
  end do
  if (is_root()) write(*, '(a,3es11.3)') '  velocity gradient tensor rms error 16,32,64:', velocity_gradient_errors
  call check_above(order(velocity_gradient_errors(1:2)), 1.8_wp, 'velocity_gradient_order_16_32')
  call check_above(order(velocity_gradient_errors(2:3)), 1.8_wp, 'velocity_gradient_order_32_64')
  call check_sampling_order()
  call test_finish()

contains

  real(wp) function order(pair)
    real(wp), intent(in) :: pair(2)
    order = log(pair(1) / pair(2)) / log(2.0_wp)
  end function order

  !> Points the same on every rank: a lattice of coordinates next to the wrap in x, y and z, on both
  !> sides of the rank boundary z = lz / 2, inside, and outside the box (they wrap); then 600
  !> seeded random points within a cell of a wrap or of the rank boundary.
  subroutine make_points()
    real(wp), parameter :: near = 1.0e-3_wp
    real(wp) :: x(6), y(3), z(9), r(3)
    type(random_stream_t) :: stream
    integer :: a, b, c, p
    x = [near * lx, lx * (1 - near), 0.37_wp * lx, -0.21_wp * lx, 1.61_wp * lx, 0.5_wp * lx]
    y = [near * ly, ly * (1 - near), 0.73_wp * ly]
    z = [near * lz, lz * (1 - near), 0.5_wp * lz * (1 - near), 0.5_wp * lz * (1 + near), 0.5_wp * lz, &
         0.29_wp * lz, 0.81_wp * lz, -0.4_wp * lz, 2.3_wp * lz]
    allocate(points(3, size(x) * size(y) * size(z) + 600))
    p = 0
    do c = 1, size(z)
      do b = 1, size(y)
        do a = 1, size(x)
          p = p + 1
          points(:, p) = [x(a), y(b), z(c)]
        end do
      end do
    end do
    call stream_seed(stream, 17_i8)
    do while (p < size(points, 2))
      r = [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
      p = p + 1
      ! Within 1/16 of the box (a cell at 16^3) of x = 0 (either side), z = lz / 2, z = 0 in turn.
      select case (mod(p, 3))
      case (0); points(:, p) = [(r(1) - 0.5_wp) * lx / 8, r(2) * ly, r(3) * lz]
      case (1); points(:, p) = [r(1) * lx, r(2) * ly, (0.5_wp + (r(3) - 0.5_wp) / 8) * lz]
      case default; points(:, p) = [r(1) * lx, (r(2) - 0.5_wp) * ly / 8, (r(3) - 0.5_wp) * lz / 8]
      end select
    end do
  end subroutine make_points

  !> Node position (m) of global indices (i, j, k) of a location (fluid_grid's conventions).
  function node_position(grid, location, i, j, k) result(position)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: location, i, j, k
    real(wp) :: position(3)
    position = [(i - 0.5_wp) * grid%dx, (j - 0.5_wp) * grid%dy, (k - 0.5_wp) * grid%dz]
    if (location == on_x_faces) position(1) = i * grid%dx
    if (location == on_y_faces) position(2) = j * grid%dy
    if (location == on_z_faces) position(3) = k * grid%dz
  end function node_position

  pure real(wp) function trilinear(r)
    real(wp), intent(in) :: r(3)
    trilinear = 0.3_wp + 1.1_wp * r(1) - 0.7_wp * r(2) + 0.45_wp * r(3) + 0.8_wp * r(1) * r(2) &
              - 0.6_wp * r(2) * r(3) + 0.9_wp * r(1) * r(3) + 1.3_wp * r(1) * r(2) * r(3)
  end function trilinear

  pure function trilinear_gradient(r) result(g)
    real(wp), intent(in) :: r(3)
    real(wp) :: g(3)
    g = [1.1_wp + 0.8_wp * r(2) + 0.9_wp * r(3) + 1.3_wp * r(2) * r(3), &
         -0.7_wp + 0.8_wp * r(1) - 0.6_wp * r(3) + 1.3_wp * r(1) * r(3), &
         0.45_wp - 0.6_wp * r(2) + 0.9_wp * r(1) + 1.3_wp * r(1) * r(2)]
  end function trilinear_gradient

  !> Trilinear field on every node of the slab including its halos (set directly from the unwrapped
  !> node positions, so the field is trilinear across the rank boundary and below z = 0 and above
  !> lz); points kept two cells away from the x and y wrap, where a non-periodic field jumps.
  subroutine check_trilinear(location)
    integer, intent(in) :: location
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: field(:, :, :), values(:), gradients(:, :), inner(:, :)
    real(wp) :: value_error, gradient_error
    integer :: i, j, k, p, q
    call grid_create(grid, 16, 8, 16, lx, ly, lz)
    call allocate_field(grid, field)
    do k = 0, grid%nz_local + 1
      do j = 0, grid%ny + 1
        do i = 0, grid%nx + 1
          field(i, j, k) = trilinear(node_position(grid, location, i, j, grid%z_offset + k))
        end do
      end do
    end do
    allocate(inner(3, size(points, 2)))
    q = 0
    do p = 1, size(points, 2)
      if (points(1, p) < 2 * grid%dx .or. points(1, p) > lx - 2 * grid%dx) cycle
      if (points(2, p) < 2 * grid%dy .or. points(2, p) > ly - 2 * grid%dy) cycle
      if (points(3, p) < 0 .or. points(3, p) >= lz) cycle
      q = q + 1
      inner(:, q) = points(:, p)
    end do
    allocate(values(q), gradients(3, q))
    call interpolate_at_points(grid, field, location, inner(:, 1:q), values)
    call gradient_at_points(grid, field, location, inner(:, 1:q), gradients)
    value_error = 0; gradient_error = 0
    do p = 1, q
      value_error = max(value_error, abs(values(p) - trilinear(inner(:, p))))
      gradient_error = max(gradient_error, maxval(abs(gradients(:, p) - trilinear_gradient(inner(:, p)))))
    end do
    ! Round-off of O(1) values and of differences divided by dx = 1/16: 1e-12.
    call check_below(value_error, 1.0e-12_wp, 'trilinear_value_exact_'//trim(names(location)))
    call check_below(gradient_error, 1.0e-12_wp, 'trilinear_gradient_exact_'//trim(names(location)))
    call check_above(real(q, wp), 30.0_wp, 'trilinear_points_tested_'//trim(names(location)))
  end subroutine check_trilinear

  !> The smooth field of this location at 16^3 (halos by the exchange): gradient_at_points against
  !> the differences of interpolate_at_points half a node spacing either side of every point.
  subroutine check_half_cell_differences(location)
    integer, intent(in) :: location
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: field(:, :, :), gradients(:, :), plus(:), minus(:), shifted(:, :)
    real(wp) :: spacing(3), largest, difference
    integer :: i, j, k, d, p
    call grid_create(grid, 16, 16, 16, lx, ly, lz)
    call allocate_field(grid, field)
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          field(i, j, k) = smooth(location, node_position(grid, location, i, j, grid%z_offset + k))
        end do
      end do
    end do
    call exchange_halos(grid, field)
    allocate(gradients(3, size(points, 2)), plus(size(points, 2)), minus(size(points, 2)))
    call gradient_at_points(grid, field, location, points, gradients)
    spacing = [grid%dx, grid%dy, grid%dz]
    largest = 0
    difference = 0
    do d = 1, 3
      shifted = points
      shifted(d, :) = points(d, :) + 0.5_wp * spacing(d)
      call interpolate_at_points(grid, field, location, shifted, plus)
      shifted(d, :) = points(d, :) - 0.5_wp * spacing(d)
      call interpolate_at_points(grid, field, location, shifted, minus)
      do p = 1, size(points, 2)
        difference = max(difference, abs(gradients(d, p) - (plus(p) - minus(p)) / spacing(d)))
        largest = max(largest, abs(gradients(d, p)))
      end do
    end do
    ! Round-off of differences of O(1) values over h = 1/32 m .. 1/8 m: 1e-12 of the gradient.
    call check_below(difference / largest, 1.0e-12_wp, 'gradient_is_half_cell_difference_'//trim(names(location)))
  end subroutine check_half_cell_differences

  !> A smooth periodic field (one per velocity component) and its gradient.
  pure real(wp) function smooth(component, r)
    integer, intent(in) :: component
    real(wp), intent(in) :: r(3)
    real(wp) :: a, b, c
    a = two_pi * r(1) / lx; b = two_pi * r(2) / ly; c = two_pi * r(3) / lz
    smooth = sin(a + 0.3_wp * component) * cos(b - 0.2_wp) * sin(c + 0.5_wp) + 0.4_wp * cos(a + 2 * c - component)
  end function smooth

  pure function smooth_gradient(component, r) result(g)
    integer, intent(in) :: component
    real(wp), intent(in) :: r(3)
    real(wp) :: g(3), a, b, c
    a = two_pi * r(1) / lx; b = two_pi * r(2) / ly; c = two_pi * r(3) / lz
    g(1) = (cos(a + 0.3_wp * component) * cos(b - 0.2_wp) * sin(c + 0.5_wp) - 0.4_wp * sin(a + 2 * c - component)) &
           * two_pi / lx
    g(2) = -sin(a + 0.3_wp * component) * sin(b - 0.2_wp) * sin(c + 0.5_wp) * two_pi / ly
    g(3) = (sin(a + 0.3_wp * component) * cos(b - 0.2_wp) * cos(c + 0.5_wp) - 0.8_wp * sin(a + 2 * c - component)) &
           * two_pi / lz
  end function smooth_gradient

  !> Rms errors over the points at cells^3 (interiors sampled, halos by the exchange: across the rank
  !> boundary and the wrap). The rms, not the largest: the error at a point depends on where it falls
  !> in its cell, which changes with the grid; over many points that averages out.
  subroutine smooth_errors(cells, value_error, gradient_error, velocity_gradient_error)
    integer, intent(in) :: cells
    real(wp), intent(out) :: value_error(4), gradient_error(4), velocity_gradient_error
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: fields(:, :, :, :), values(:), gradients(:, :), tensor(:, :, :)
    integer :: location, i, j, k, p
    call grid_create(grid, cells, cells, cells, lx, ly, lz)
    allocate(fields(0:cells + 1, 0:cells + 1, 0:grid%nz_local + 1, 4))
    allocate(values(size(points, 2)), gradients(3, size(points, 2)), tensor(3, 3, size(points, 2)))
    do location = 1, 4
      do k = 1, grid%nz_local
        do j = 1, cells
          do i = 1, cells
            fields(i, j, k, location) = smooth(location, node_position(grid, location, i, j, grid%z_offset + k))
          end do
        end do
      end do
      call exchange_halos(grid, fields(:, :, :, location))
      call interpolate_at_points(grid, fields(:, :, :, location), location, points, values)
      call gradient_at_points(grid, fields(:, :, :, location), location, points, gradients)
      value_error(location) = 0; gradient_error(location) = 0
      do p = 1, size(points, 2)
        value_error(location) = value_error(location) + (values(p) - smooth(location, points(:, p)))**2
        gradient_error(location) = gradient_error(location) &
                                 + sum((gradients(:, p) - smooth_gradient(location, points(:, p)))**2)
      end do
      value_error(location) = sqrt(value_error(location) / size(points, 2))
      gradient_error(location) = sqrt(gradient_error(location) / size(points, 2))
    end do
    call velocity_gradient_at_points(grid, fields(:, :, :, 1), fields(:, :, :, 2), fields(:, :, :, 3), points, tensor)
    velocity_gradient_error = 0
    do p = 1, size(points, 2)
      do i = 1, 3
        velocity_gradient_error = velocity_gradient_error + sum((tensor(i, :, p) - smooth_gradient(i, points(:, p)))**2)
      end do
    end do
    velocity_gradient_error = sqrt(velocity_gradient_error / size(points, 2))
  end subroutine smooth_errors
  !> The point coupling's sampling (module header, last item) on the smooth fields at 16^3.
  subroutine check_sampling_order()
    type(fluid_grid_t) :: grid
    real(wp), allocatable :: fields(:, :, :, :), values(:, :), tensor(:, :, :), velocity(:, :), gradients(:, :, :)
    integer, allocatable :: visit(:), seen(:), key(:)
    integer :: location, i, j, k, m, ordered
    real(wp) :: difference, largest
    call grid_create(grid, 16, 16, 16, lx, ly, lz)
    allocate(fields(0:17, 0:17, 0:grid%nz_local + 1, 3), values(3, size(points, 2)), tensor(3, 3, size(points, 2)))
    allocate(velocity(3, size(points, 2)), gradients(3, 3, size(points, 2)))
    do location = 1, 3
      do k = 1, grid%nz_local
        do j = 1, 16
          do i = 1, 16
            fields(i, j, k, location) = smooth(location, node_position(grid, location, i, j, grid%z_offset + k))
          end do
        end do
      end do
      call exchange_halos(grid, fields(:, :, :, location))
      call interpolate_at_points(grid, fields(:, :, :, location), location, points, values(location, :))
    end do
    call velocity_gradient_at_points(grid, fields(:, :, :, 1), fields(:, :, :, 2), fields(:, :, :, 3), points, tensor)
    call sampling_order(grid, points, visit)
    call velocity_and_gradient_at_points(grid, fields(:, :, :, 1), fields(:, :, :, 2), fields(:, :, :, 3), points, &
                                         velocity, gradients, visit)
    ! The order: cell keys (z, y, x) never decrease along this rank's list; no point twice.
    allocate(key(size(visit)), seen(size(points, 2)))
    do m = 1, size(visit)
      key(m) = cell(points(1, visit(m)), lx, 16) + 16 * (cell(points(2, visit(m)), ly, 16) &
               + 16 * cell(points(3, visit(m)), lz, 16))
    end do
    ordered = merge(1, 0, all(key(2:) >= key(:size(key) - 1)))
    seen = 0
    seen(visit) = 1
    ordered = merge(ordered, 0, sum(seen) == size(visit) .and. size(visit) > 0)
    call MPI_Allreduce(MPI_IN_PLACE, ordered, 1, MPI_INTEGER, MPI_MIN, MPI_COMM_WORLD)
    call MPI_Allreduce(MPI_IN_PLACE, seen, size(seen), MPI_INTEGER, MPI_SUM, MPI_COMM_WORLD)
    call check(ordered == 1, 'sampling_order_in_cell_order_no_point_twice')
    call check(all(seen >= 1), 'sampling_order_every_point_on_some_rank')
    difference = max(maxval(abs(velocity - values)) / maxval(abs(values)), maxval(abs(gradients - tensor)) / maxval(abs(tensor)))
    call check_below(difference, 1.0e-13_wp, 'sampled_velocity_and_gradient_as_the_separate_routines')
  end subroutine check_sampling_order

  !> 0-based cell of coordinate x (wrapped into the period) of n cells.
  integer function cell(x, length, n)
    real(wp), intent(in) :: x, length
    integer, intent(in) :: n
    cell = min(n - 1, int(modulo(x, length) / (length / n)))
  end function cell
end program test_field_interpolation
