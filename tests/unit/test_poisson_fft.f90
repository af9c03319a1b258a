! ranks: 2
! checks: 3
!> Tests of poisson_fft on an anisotropic grid split over 2 ranks.
!> Manufactured discrete solutions: pick phi, form rhs = L phi with the same 7-point stencil the
!> solver inverts; the FFT solve with the modified wavenumbers (docs/physics.md section 2) must return
!> phi to round-off. Reference: the exact discrete eigenvalues, so the only error is round-off.
program test_poisson_fft
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, global_max, global_sum
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use fluid_grid, only: fluid_grid_t, grid_create, allocate_field, exchange_halos, x_centre, y_centre, z_centre
  use poisson_fft, only: poisson_fft_t, poisson_create, poisson_solve, helmholtz_solve
  use momentum_terms, only: laplacian
  use physical_constants, only: two_pi
  use test_framework, only: test_start, test_finish, check_below
  implicit none
  type(fluid_grid_t) :: grid
  type(poisson_fft_t) :: solver
  real(wp), allocatable :: exact(:, :, :), rhs(:, :, :), solution(:, :, :), lap(:, :, :)
  real(wp) :: mean, error, scale, coefficient
  integer :: i, j, k

  call parallel_start()
  call test_start('poisson_fft')
  call grid_create(grid, 24, 16, 12, 1.0_wp, 0.7_wp, 0.5_wp)
  call poisson_create(solver, grid, 'estimate')
  call allocate_field(grid, exact); call allocate_field(grid, rhs)
  call allocate_field(grid, solution); call allocate_field(grid, lap)

  ! A rough field (random values: every wavenumber present, Nyquist included) with zero mean.
  call fill_random(exact)
  mean = global_sum(sum(exact(1:grid%nx, 1:grid%ny, 1:grid%nz_local))) / grid%cells_total
  exact(1:grid%nx, 1:grid%ny, 1:grid%nz_local) = exact(1:grid%nx, 1:grid%ny, 1:grid%nz_local) - mean
  call exchange_halos(grid, exact)
  call laplacian(grid, exact, rhs)
  call poisson_solve(solver, rhs, solution)
  call check_below(relative_error(), 1.0e-12_wp, 'random_discrete_solution_to_roundoff')

  ! A smooth field: sin/cos products of several wavenumbers.
  do k = 1, grid%nz_local
    do j = 1, grid%ny
      do i = 1, grid%nx
        exact(i, j, k) = sin(two_pi * x_centre(grid, i)) * cos(2 * two_pi * y_centre(grid, j) / 0.7_wp) &
                       + cos(3 * two_pi * z_centre(grid, k) / 0.5_wp) * sin(5 * two_pi * x_centre(grid, i))
      end do
    end do
  end do
  call exchange_halos(grid, exact)
  call laplacian(grid, exact, rhs)
  call poisson_solve(solver, rhs, solution)
  call check_below(relative_error(), 1.0e-12_wp, 'smooth_discrete_solution_to_roundoff')

  ! Helmholtz (I - c L) x = f, the Crank-Nicolson operator, with c = nu dt / 2 of a typical step.
  coefficient = 0.3_wp * grid%dx**2
  call fill_random(exact)
  call exchange_halos(grid, exact)
  call laplacian(grid, exact, lap)
  solution = exact - coefficient * lap
  call helmholtz_solve(solver, solution, coefficient)
  call check_below(relative_error(), 1.0e-12_wp, 'helmholtz_discrete_solution_to_roundoff')
  call test_finish()

contains

  subroutine fill_random(field)
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    type(random_stream_t) :: stream
    integer :: kg
    call stream_seed(stream, 11_i8)
    do kg = 1, grid%nz
      do j = 1, grid%ny
        do i = 1, grid%nx
          scale = stream_uniform(stream) - 0.5_wp
          k = kg - grid%z_offset
          if (k >= 1 .and. k <= grid%nz_local) field(i, j, k) = scale
        end do
      end do
    end do
  end subroutine fill_random

  real(wp) function relative_error()
    error = global_max(maxval(abs(solution(1:grid%nx, 1:grid%ny, 1:grid%nz_local) &
                                  - exact(1:grid%nx, 1:grid%ny, 1:grid%nz_local))))
    scale = global_max(maxval(abs(exact(1:grid%nx, 1:grid%ny, 1:grid%nz_local))))
    relative_error = error / scale
  end function relative_error
end program test_poisson_fft
