!> The sampling of the fluid at point-particle centres (docs/studies/performance.md, "Point
!> particles, many"): velocity_and_gradient_at_points of field_interpolation on a random 128^3
!> field at N random points visited in the order of their grid rows, as the point coupling visits
!> them. Prints N, the median of 15 repetitions (ms of CPU time of the process: on a shared machine
!> the wall time measures the other jobs) and ns per point, and a checksum of the values (it must
!> not change when the interpolation is rearranged).
!> Usage: mpirun -np R bench_point_sampling [N] (default 100000).
program bench_point_sampling
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use sample_statistics, only: median
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use field_interpolation, only: velocity_and_gradient_at_points
  implicit none
  integer, parameter :: cells = 128, repeats = 15
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :), points(:, :), velocity(:, :), gradients(:, :, :)
  real(wp), allocatable :: keys(:)
  integer, allocatable :: order(:)
  real(wp) :: seconds(repeats), t0, t1
  integer :: n, p, r, i, j, k
  character(len=32) :: argument

  call parallel_start()
  n = 100000
  if (command_argument_count() >= 1) then
    call get_command_argument(1, argument)
    read(argument, *) n
  end if
  call grid_create(grid, cells, cells, cells, 1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp)
  call allocate_field(grid, u)
  call allocate_field(grid, v)
  call allocate_field(grid, w)
  call stream_seed(stream, 7_i8)
  ! Values on the local nodes and their halo copies alike (the sampling reads the halos).
  do k = 0, grid%nz_local + 1
    do j = 0, grid%ny + 1
      do i = 0, grid%nx + 1
        u(i, j, k) = stream_uniform(stream) - 0.5_wp
        v(i, j, k) = stream_uniform(stream) - 0.5_wp
        w(i, j, k) = stream_uniform(stream) - 0.5_wp
      end do
    end do
  end do
  call stream_seed(stream, 11_i8)
  allocate(points(3, n), velocity(3, n), gradients(3, 3, n), keys(n))
  do p = 1, n
    points(:, p) = [stream_uniform(stream) * grid%lx, stream_uniform(stream) * grid%ly, stream_uniform(stream) * grid%lz]
    keys(p) = floor(points(3, p) / grid%dz) * grid%ny + floor(points(2, p) / grid%dy) + points(1, p) / grid%lx
  end do
  order = sorted_order(keys)
  points = points(:, order)
  do r = 1, repeats
    call cpu_time(t0)
    call velocity_and_gradient_at_points(grid, u, v, w, points, velocity, gradients)
    call cpu_time(t1)
    seconds(r) = t1 - t0
  end do
  if (is_root()) write(*, '(a,i0,a,f9.2,a,f8.1,a,es24.16)') 'points ', n, '  sampling (ms) ', &
      1.0e3_wp * median(seconds), '  ns per point ', 1.0e9_wp * median(seconds) / n, &
      '  checksum ', sum(velocity) + sum(gradients) * 1.0e-6_wp
  call parallel_stop()

contains

  !> The permutation that sorts keys ascending (a merge sort; the bench's set-up only).
  recursive function sorted_order(keys) result(order)
    real(wp), intent(in) :: keys(:)
    integer, allocatable :: order(:), left(:), right(:)
    integer :: half, a, b, m
    allocate(order(size(keys)))
    if (size(keys) <= 1) then
      order = [(m, m = 1, size(keys))]
      return
    end if
    half = size(keys) / 2
    left = sorted_order(keys(1:half))
    right = sorted_order(keys(half + 1:)) + half
    a = 1
    b = 1
    do m = 1, size(keys)
      if (b > size(right)) then
        order(m) = left(a); a = a + 1
      else if (a > size(left)) then
        order(m) = right(b); b = b + 1
      else if (keys(left(a)) <= keys(right(b))) then
        order(m) = left(a); a = a + 1
      else
        order(m) = right(b); b = b + 1
      end if
    end do
  end function sorted_order
end program bench_point_sampling
