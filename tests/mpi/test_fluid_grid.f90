! ranks: 2
! checks: 5
!> Tests of fluid_grid: the slab layout matches FFTW-MPI's and the halo exchange fills every
!> halo cell (faces, edges, corners) with its periodic image.
program test_fluid_grid
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, n_ranks, global_max, global_sum
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field, exchange_halos, z_centre, x_face
  use test_framework, only: test_start, test_finish, check_equal, check_below, check_close
  implicit none
  type(fluid_grid_t) :: grid
  real(wp), allocatable :: field(:, :, :)
  integer :: i, j, k, kg
  real(wp) :: error, planes

  call parallel_start()
  call test_start('fluid_grid')
  call grid_create(grid, 6, 4, 8, 1.0_wp, 2.0_wp, 4.0_wp)

  ! Equal slabs (8 planes on n ranks) that tile the box: FFTW's layout for nz divisible by n.
  call check_equal(grid%nz_local, 8 / n_ranks, 'slab_planes_equal')
  planes = global_sum(real(grid%nz_local, wp))
  call check_close(planes, 8.0_wp, 0.0_wp, 'slabs_tile_the_box')
  call check_close(z_centre(grid, 1), (grid%z_offset + 0.5_wp) * 0.5_wp, 1.0e-15_wp, 'z_centre_position')
  call check_close(x_face(grid, 6), 1.0_wp, 1.0e-15_wp, 'last_x_face_at_box_edge')

  ! A field whose value encodes its global cell: after the exchange every halo value must equal
  ! the value of its periodic image (exact copies, so the tolerance is zero).
  call allocate_field(grid, field)
  do k = 1, grid%nz_local
    do j = 1, grid%ny
      do i = 1, grid%nx
        field(i, j, k) = code(i, j, grid%z_offset + k)
      end do
    end do
  end do
  call exchange_halos(grid, field)
  error = 0.0_wp
  do k = 0, grid%nz_local + 1
    kg = grid%z_offset + k
    do j = 0, grid%ny + 1
      do i = 0, grid%nx + 1
        error = max(error, abs(field(i, j, k) - code(i, j, kg)))
      end do
    end do
  end do
  error = global_max(error)
  call check_below(error, 0.0_wp, 'halo_values_are_periodic_images')
  call test_finish()

contains

  !> The value stored in global cell (i,j,k) after wrapping indices into the box.
  real(wp) function code(i, j, k)
    integer, intent(in) :: i, j, k
    code = modulo(i - 1, 6) + 10 * modulo(j - 1, 4) + 100 * modulo(k - 1, 8)
  end function code
end program test_fluid_grid
