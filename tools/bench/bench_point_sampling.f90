!> The sampling of the fluid at point-particle centres (docs/studies/performance.md, "Point
!> particles, many"): velocity_and_gradient_at_points of field_interpolation on a random 128^3
!> field at N random points visited in the order of their grid cells (sampling_order), as the point
!> coupling visits them. Prints N, the median of 15 repetitions (ms of CPU time of the process: on a
!> shared machine the wall time measures the other jobs) and ns per point, the time of the ordering
!> (once per fluid step in the coupling, for its two samples), and a checksum of the values (it must
!> not change when the interpolation is rearranged).
!> Usage: mpirun -np R bench_point_sampling [N] (default 100000).
program bench_point_sampling
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use sample_statistics, only: median
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field
  use field_interpolation, only: velocity_and_gradient_at_points, sampling_order
  implicit none
  integer, parameter :: cells = 128, repeats = 15
  type(fluid_grid_t) :: grid
  type(random_stream_t) :: stream
  real(wp), allocatable :: u(:, :, :), v(:, :, :), w(:, :, :), points(:, :), velocity(:, :), gradients(:, :, :)
  integer, allocatable :: visit(:)
  real(wp) :: seconds(repeats), ordering(repeats), t0, t1
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
  allocate(points(3, n), velocity(3, n), gradients(3, 3, n))
  do p = 1, n
    points(:, p) = [stream_uniform(stream) * grid%lx, stream_uniform(stream) * grid%ly, stream_uniform(stream) * grid%lz]
  end do
  do r = 1, repeats
    call cpu_time(t0)
    call sampling_order(grid, points, visit)
    call cpu_time(t1)
    ordering(r) = t1 - t0
    call velocity_and_gradient_at_points(grid, u, v, w, points, velocity, gradients, visit)
    call cpu_time(t0)
    seconds(r) = t0 - t1
  end do
  if (is_root()) write(*, '(a,i0,a,f9.2,a,f8.1,a,f7.2,a,es24.16)') 'points ', n, '  sampling (ms) ', &
      1.0e3_wp * median(seconds), '  ns per point ', 1.0e9_wp * median(seconds) / n, '  ordering (ms) ', &
      1.0e3_wp * median(ordering), '  checksum ', sum(velocity) + sum(gradients) * 1.0e-6_wp
  call parallel_stop()
end program bench_point_sampling
