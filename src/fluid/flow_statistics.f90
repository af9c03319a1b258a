!> Statistics of the resolved velocity field (homogeneous box): fluctuation r.m.s. and kinetic
!> energy, dissipation from the velocity gradients, power input, the isotropic-turbulence length
!> scales and Reynolds number, and the shell-averaged energy spectrum E(k).
!>
!> Definitions (Pope 2000, "Turbulent Flows", sections 5.4, 6.1, 6.5; u' = u_rms per component):
!>   u'_c = sqrt(<(u_c - <u_c>)^2>),  u' = sqrt((u'_x^2 + u'_y^2 + u'_z^2)/3),  k_E = 3 u'^2 / 2
!>   epsilon = nu <d_j u_i d_j u_i> with forward differences on the MAC grid. In the periodic box
!>     this equals 2 nu <S_ij S_ij> on average, and it is exactly the energy the discrete viscous
!>     operator removes (summation by parts: -<u . L_h u> = <|D+ u|^2>), so a stationary run has
!>     <f.u> = epsilon with it (the advection is energy conserving, the pressure does no work).
!>   lambda = sqrt(15 nu u'^2 / epsilon),  Re_lambda = u' lambda / nu,  eta = (nu^3 / epsilon)^(1/4)
!>   kappa_max = pi / max(dx, dy, dz) (the largest wavenumber a second-order grid carries)
!>   E(k): FFT of each component on its own faces (the half-cell shifts change only phases), energy
!>     1/2 |u^(k)|^2 summed over the shell |k| in [(s - 1/2) kappa0, (s + 1/2) kappa0), kappa0 = 2 pi / L_max,
!>     divided by kappa0, so sum_s E(s kappa0) kappa0 = k_E (Parseval); shell 0 (the mean) excluded.
!>   L_int = pi / (2 u'^2) integral E(k)/k dk.
!> Every quantity is a global (all-rank) value, the same on every rank.
module flow_statistics
  use, intrinsic :: iso_c_binding, only: c_ptr, c_double, c_double_complex, c_intptr_t, c_f_pointer, &
                                         c_associated, c_null_ptr
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM
  use fftw_interface, only: fftw_mpi_plan_dft_r2c_3d, fftw_mpi_execute_dft_r2c, fftw_alloc_complex, fftw_free, &
                            fftw_destroy_plan, FFTW_ESTIMATE, FFTW_MPI_TRANSPOSED_OUT
  use agglo_kinds, only: wp
  use physical_constants, only: pi, two_pi
  use fluid_grid, only: fluid_grid_t, exchange_halos
  use parallel_env, only: world, mpi_wp, global_sum
  implicit none
  private
  public :: flow_statistics_t, flow_statistics_init, flow_statistics_free, compute_flow_statistics

  type :: flow_statistics_t
    ! Results of the last compute_flow_statistics (SI units, per unit mass where it applies).
    real(wp) :: u_rms = 0              !< m/s, u' (per-component average)
    real(wp) :: u_rms_component(3) = 0 !< m/s, u'_x, u'_y, u'_z
    real(wp) :: mean_velocity(3) = 0   !< m/s, box average of each component
    real(wp) :: kinetic_energy = 0     !< m^2/s^2, 1/2 <|u - <u>|^2>
    real(wp) :: dissipation = 0        !< m^2/s^3, nu <d_j u_i d_j u_i>
    real(wp) :: power_input = 0        !< m^2/s^3, <f.u> as given by the caller (0 without forcing)
    real(wp) :: taylor_microscale = 0  !< m
    real(wp) :: re_lambda = 0          !< Taylor-Reynolds number
    real(wp) :: kolmogorov_length = 0  !< m, eta
    real(wp) :: kmax_eta = 0           !< kappa_max eta (resolution: >= 1 is well resolved)
    real(wp) :: integral_length = 0    !< m
    real(wp) :: spectrum_energy = 0    !< m^2/s^2, sum_s E_s kappa0 (= kinetic_energy, Parseval)
    real(wp), allocatable :: wavenumber(:)   !< (n_shells) 1/m, s kappa0 for s = 1 .. n_shells
    real(wp), allocatable :: spectrum(:)     !< (n_shells) m^3/s^2, E(k)
    ! FFT workspace (FFTW-MPI r2c with transposed output, the slab layout of fluid_grid).
    type(c_ptr) :: plan = c_null_ptr, buffer = c_null_ptr
    real(c_double), pointer :: real_data(:,:,:) => null()
    complex(c_double_complex), pointer :: spectral_data(:,:,:) => null()
    real(wp) :: kappa0 = 0
    integer :: n_shells = 0
  end type flow_statistics_t

contains

  !> The FFT plan and spectrum arrays (collective).
  subroutine flow_statistics_init(stats, grid)
    type(flow_statistics_t), intent(inout) :: stats
    type(fluid_grid_t), intent(in) :: grid
    integer :: nxh
    call flow_statistics_free(stats)
    nxh = grid%nx / 2 + 1
    stats%buffer = fftw_alloc_complex(grid%slab%complex_alloc)
    call c_f_pointer(stats%buffer, stats%real_data, [2 * nxh, grid%ny, grid%nz_local])
    call c_f_pointer(stats%buffer, stats%spectral_data, [nxh, grid%nz, grid%slab%ny_local_spectral])
    stats%plan = fftw_mpi_plan_dft_r2c_3d(int(grid%nz, c_intptr_t), int(grid%ny, c_intptr_t), &
        int(grid%nx, c_intptr_t), stats%real_data, stats%spectral_data, world%MPI_VAL, &
        ior(FFTW_ESTIMATE, FFTW_MPI_TRANSPOSED_OUT))
    stats%kappa0 = two_pi / max(grid%lx, grid%ly, grid%lz)
    ! The largest |k| on the grid is |(pi/dx, pi/dy, pi/dz)|.
    stats%n_shells = nint(norm2([pi / grid%dx, pi / grid%dy, pi / grid%dz]) / stats%kappa0) + 1
    allocate(stats%wavenumber(stats%n_shells), stats%spectrum(stats%n_shells))
    call set_wavenumbers(stats)
  end subroutine flow_statistics_init

  subroutine set_wavenumbers(stats)
    type(flow_statistics_t), intent(inout) :: stats
    integer :: s
    do s = 1, stats%n_shells
      stats%wavenumber(s) = s * stats%kappa0
    end do
  end subroutine set_wavenumbers

  subroutine flow_statistics_free(stats)
    type(flow_statistics_t), intent(inout) :: stats
    if (c_associated(stats%plan)) call fftw_destroy_plan(stats%plan)
    if (c_associated(stats%buffer)) call fftw_free(stats%buffer)
    stats%plan = c_null_ptr
    stats%buffer = c_null_ptr
    nullify(stats%real_data, stats%spectral_data)
    if (allocated(stats%wavenumber)) deallocate(stats%wavenumber)
    if (allocated(stats%spectrum)) deallocate(stats%spectrum)
  end subroutine flow_statistics_free

  !> All statistics of the velocity (u, v, w) on the MAC faces (collective). The halos are
  !> refreshed here (the interior is not changed). power_input: <f.u> from the forcing, if any.
  subroutine compute_flow_statistics(stats, grid, u, v, w, viscosity, power_input)
    type(flow_statistics_t), intent(inout) :: stats
    type(fluid_grid_t), intent(inout) :: grid
    real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: viscosity
    real(wp), intent(in), optional :: power_input
    real(wp) :: cells, gradient_squares, u_prime_squared, inverse_spacing(3)

    if (.not. c_associated(stats%plan)) call flow_statistics_init(stats, grid)
    cells = real(grid%nx, wp) * real(grid%ny, wp) * real(grid%nz, wp)
    call exchange_halos(grid, u)
    call exchange_halos(grid, v)
    call exchange_halos(grid, w)

    ! Means and fluctuation r.m.s.
    stats%mean_velocity(1) = global_sum(sum(u(1:grid%nx, 1:grid%ny, 1:grid%nz_local))) / cells
    stats%mean_velocity(2) = global_sum(sum(v(1:grid%nx, 1:grid%ny, 1:grid%nz_local))) / cells
    stats%mean_velocity(3) = global_sum(sum(w(1:grid%nx, 1:grid%ny, 1:grid%nz_local))) / cells
    stats%u_rms_component(1) = sqrt(global_sum(sum((u(1:grid%nx, 1:grid%ny, 1:grid%nz_local) &
        - stats%mean_velocity(1))**2)) / cells)
    stats%u_rms_component(2) = sqrt(global_sum(sum((v(1:grid%nx, 1:grid%ny, 1:grid%nz_local) &
        - stats%mean_velocity(2))**2)) / cells)
    stats%u_rms_component(3) = sqrt(global_sum(sum((w(1:grid%nx, 1:grid%ny, 1:grid%nz_local) &
        - stats%mean_velocity(3))**2)) / cells)
    u_prime_squared = sum(stats%u_rms_component**2) / 3.0_wp
    stats%u_rms = sqrt(u_prime_squared)
    stats%kinetic_energy = 1.5_wp * u_prime_squared

    ! Dissipation: nu times the mean of the squared forward differences of every component.
    inverse_spacing = [1.0_wp / grid%dx, 1.0_wp / grid%dy, 1.0_wp / grid%dz]
    gradient_squares = squared_forward_differences(u, grid, inverse_spacing) + &
                       squared_forward_differences(v, grid, inverse_spacing) + &
                       squared_forward_differences(w, grid, inverse_spacing)
    stats%dissipation = viscosity * global_sum(gradient_squares) / cells
    stats%power_input = 0.0_wp
    if (present(power_input)) stats%power_input = power_input

    ! Length scales (undefined for a fluid at rest: left at 0).
    stats%taylor_microscale = 0; stats%re_lambda = 0; stats%kolmogorov_length = 0; stats%kmax_eta = 0
    if (stats%dissipation > 0.0_wp) then
      stats%taylor_microscale = sqrt(15.0_wp * viscosity * u_prime_squared / stats%dissipation)
      stats%re_lambda = stats%u_rms * stats%taylor_microscale / viscosity
      stats%kolmogorov_length = (viscosity**3 / stats%dissipation)**0.25_wp
      stats%kmax_eta = pi / max(grid%dx, grid%dy, grid%dz) * stats%kolmogorov_length
    end if

    ! Spectrum.
    stats%spectrum = 0.0_wp
    call add_component_spectrum(stats, grid, u)
    call add_component_spectrum(stats, grid, v)
    call add_component_spectrum(stats, grid, w)
    call MPI_Allreduce(MPI_IN_PLACE, stats%spectrum, stats%n_shells, mpi_wp, MPI_SUM, world)
    stats%spectrum_energy = sum(stats%spectrum)
    stats%integral_length = 0.0_wp
    if (u_prime_squared > 0.0_wp) stats%integral_length = pi / (2.0_wp * u_prime_squared) * &
        sum(stats%spectrum / stats%wavenumber)
    stats%spectrum = stats%spectrum / stats%kappa0    ! shell energy -> spectral density E(k)
  end subroutine compute_flow_statistics

  !> Local sum over the interior of (D+_x q)^2 + (D+_y q)^2 + (D+_z q)^2 (halos must be current).
  function squared_forward_differences(q, grid, inverse_spacing) result(total)
    real(wp), intent(in) :: q(0:, 0:, 0:)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: inverse_spacing(3)
    real(wp) :: total
    integer :: i, j, k
    total = 0.0_wp
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          total = total + ((q(i + 1, j, k) - q(i, j, k)) * inverse_spacing(1))**2 &
                        + ((q(i, j + 1, k) - q(i, j, k)) * inverse_spacing(2))**2 &
                        + ((q(i, j, k + 1) - q(i, j, k)) * inverse_spacing(3))**2
        end do
      end do
    end do
  end function squared_forward_differences

  !> Add this rank's part of 1/2 |q^(k)|^2 per shell (mean excluded). The r2c output holds
  !> kx >= 0 only: interior kx columns stand for their conjugate twins too (weight 2).
  subroutine add_component_spectrum(stats, grid, q)
    type(flow_statistics_t), intent(inout) :: stats
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: q(0:, 0:, 0:)
    integer :: p, r, jj, shell, nxh, ky_index, kz_index
    real(wp) :: kx, ky, kz, weight, normalisation
    nxh = grid%nx / 2 + 1
    stats%real_data(1:grid%nx, :, :) = q(1:grid%nx, 1:grid%ny, 1:grid%nz_local)
    call fftw_mpi_execute_dft_r2c(stats%plan, stats%real_data, stats%spectral_data)
    normalisation = 1.0_wp / (real(grid%nx, wp) * real(grid%ny, wp) * real(grid%nz, wp))**2
    do jj = 1, grid%slab%ny_local_spectral
      ky_index = wrapped(grid%slab%y_offset_spectral + jj - 1, grid%ny)
      ky = two_pi * ky_index / grid%ly
      do r = 1, grid%nz
        kz_index = wrapped(r - 1, grid%nz)
        kz = two_pi * kz_index / grid%lz
        do p = 1, nxh
          kx = two_pi * (p - 1) / grid%lx
          weight = 2.0_wp
          if (p == 1 .or. 2 * (p - 1) == grid%nx) weight = 1.0_wp
          shell = nint(sqrt(kx**2 + ky**2 + kz**2) / stats%kappa0)
          if (shell < 1) cycle
          shell = min(shell, stats%n_shells)
          stats%spectrum(shell) = stats%spectrum(shell) + &
              0.5_wp * weight * normalisation * abs(stats%spectral_data(p, r, jj))**2
        end do
      end do
    end do
  end subroutine add_component_spectrum

  !> Signed wavenumber index of DFT entry index (0-based) among n.
  pure integer function wrapped(index, n)
    integer, intent(in) :: index, n
    wrapped = index
    if (2 * index > n) wrapped = index - n
  end function wrapped
end module flow_statistics
