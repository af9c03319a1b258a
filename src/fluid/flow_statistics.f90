!> Statistics of the resolved velocity field (homogeneous box): fluctuation r.m.s. and kinetic
!> energy, dissipation from the velocity gradients, power input, the isotropic-turbulence length
!> scales and Reynolds number, and the shell-averaged energy spectrum E(k).
!>
!> Definitions (Pope 2000, "Turbulent Flows", sections 5.4, 6.1, 6.5; u' = u_rms per component):
!>   u'_c = sqrt(<(u_c - <u_c>)^2>),  u' = sqrt((u'_x^2 + u'_y^2 + u'_z^2)/3),  k_E = 3 u'^2 / 2
!>   epsilon = nu <d_j u_i d_j u_i> with forward differences on the MAC grid (fluid_diagnostics, the one
!>     place it is computed). In the periodic box
!>     this equals 2 nu <S_ij S_ij> on average, and it is exactly the energy the discrete viscous
!>     operator removes (summation by parts: -<u . L_h u> = <|D+ u|^2>), so a stationary run has
!>     <f.u> = epsilon with it (the advection is energy conserving, the pressure does no work).
!>   lambda = sqrt(15 nu u'^2 / epsilon),  Re_lambda = u' lambda / nu,  eta = (nu^3 / epsilon)^(1/4)
!>   kappa_max = pi / max(dx, dy, dz) (the largest wavenumber a second-order grid carries)
!>   E(k): FFT of each component on its own faces (the half-cell shifts change only phases), energy
!>     1/2 |u^(k)|^2 summed over the shell |k| in [(s - 1/2) kappa0, (s + 1/2) kappa0), kappa0 = 2 pi / L_max,
!>     divided by kappa0, so sum_s E(s kappa0) kappa0 = k_E (Parseval); shell 0 (the mean) excluded.
!>   L_int = pi / (2 u'^2) integral E(k)/k dk.
!> Every quantity is a global (all-rank) value, the same on every rank. The spectrum uses the solver's
!> FFT plans, buffer and wavenumbers (poisson_fft): between two steps the buffer is scratch.
module flow_statistics
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM
  use agglo_kinds, only: wp
  use physical_constants, only: pi, two_pi
  use parallel_env, only: world, mpi_wp, global_sum
  use poisson_fft, only: fft_forward => forward
  use fluid_solver, only: fluid_solver_t, fluid_exchange_velocity
  use fluid_diagnostics, only: fluid_statistics_t, compute_fluid_statistics
  implicit none
  private
  public :: flow_statistics_t, compute_flow_statistics

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
    real(wp) :: kappa0 = 0
    integer :: n_shells = 0
  end type flow_statistics_t

contains

  !> The shells of the spectrum for the solver's grid.
  subroutine set_shells(stats, solver)
    type(flow_statistics_t), intent(inout) :: stats
    type(fluid_solver_t), intent(in) :: solver
    integer :: s
    associate (grid => solver%grid)
      stats%kappa0 = two_pi / max(grid%lx, grid%ly, grid%lz)
      ! The largest |k| on the grid is |(pi/dx, pi/dy, pi/dz)|.
      stats%n_shells = nint(norm2([pi / grid%dx, pi / grid%dy, pi / grid%dz]) / stats%kappa0) + 1
    end associate
    if (allocated(stats%wavenumber)) deallocate(stats%wavenumber, stats%spectrum)
    allocate(stats%wavenumber(stats%n_shells), stats%spectrum(stats%n_shells))
    do s = 1, stats%n_shells
      stats%wavenumber(s) = s * stats%kappa0
    end do
  end subroutine set_shells

  !> All statistics of the solver's velocity (collective). The velocity halos are refreshed here
  !> (the interior is not changed); the solver's FFT buffer is overwritten. power_input: <f.u> from
  !> the forcing, if any.
  subroutine compute_flow_statistics(stats, solver, power_input)
    type(flow_statistics_t), intent(inout) :: stats
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in), optional :: power_input
    type(fluid_statistics_t) :: diagnostics
    real(wp) :: cells, u_prime_squared, viscosity

    if (.not. allocated(stats%spectrum)) call set_shells(stats, solver)
    call fluid_exchange_velocity(solver)
    viscosity = solver%viscosity
    associate (grid => solver%grid, u => solver%u, v => solver%v, w => solver%w)
      cells = real(grid%nx, wp) * real(grid%ny, wp) * real(grid%nz, wp)

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
    end associate
    u_prime_squared = sum(stats%u_rms_component**2) / 3.0_wp
    stats%u_rms = sqrt(u_prime_squared)
    stats%kinetic_energy = 1.5_wp * u_prime_squared

    ! Dissipation: nu times the mean of the squared forward differences of every component.
    call compute_fluid_statistics(solver, 0.0_wp, diagnostics)
    stats%dissipation = diagnostics%dissipation
    stats%power_input = 0.0_wp
    if (present(power_input)) stats%power_input = power_input

    ! Length scales (undefined for a fluid at rest: left at 0).
    stats%taylor_microscale = 0; stats%re_lambda = 0; stats%kolmogorov_length = 0; stats%kmax_eta = 0
    if (stats%dissipation > 0.0_wp) then
      stats%taylor_microscale = sqrt(15.0_wp * viscosity * u_prime_squared / stats%dissipation)
      stats%re_lambda = stats%u_rms * stats%taylor_microscale / viscosity
      stats%kolmogorov_length = (viscosity**3 / stats%dissipation)**0.25_wp
      stats%kmax_eta = pi / max(solver%grid%dx, solver%grid%dy, solver%grid%dz) * stats%kolmogorov_length
    end if

    ! Spectrum.
    stats%spectrum = 0.0_wp
    call add_component_spectrum(stats, solver, solver%u)
    call add_component_spectrum(stats, solver, solver%v)
    call add_component_spectrum(stats, solver, solver%w)
    call MPI_Allreduce(MPI_IN_PLACE, stats%spectrum, stats%n_shells, mpi_wp, MPI_SUM, world)
    stats%spectrum_energy = sum(stats%spectrum)
    stats%integral_length = 0.0_wp
    if (u_prime_squared > 0.0_wp) stats%integral_length = pi / (2.0_wp * u_prime_squared) * &
        sum(stats%spectrum / stats%wavenumber)
    stats%spectrum = stats%spectrum / stats%kappa0    ! shell energy -> spectral density E(k)
  end subroutine compute_flow_statistics

  !> Add this rank's part of 1/2 |q^(k)|^2 per shell (mean excluded), with the solver's forward
  !> transform and its physical wavenumbers. The r2c output holds kx >= 0 only: interior kx
  !> columns stand for their conjugate twins too (weight 2).
  subroutine add_component_spectrum(stats, solver, q)
    type(flow_statistics_t), intent(inout) :: stats
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: q(0:, 0:, 0:)
    integer :: p, r, jj, shell
    real(wp) :: weight, normalisation
    call fft_forward(solver%poisson, q)
    associate (fft => solver%poisson)
      normalisation = 1.0_wp / (real(fft%nx, wp) * real(fft%ny, wp) * real(fft%nz, wp))**2
      do jj = 1, fft%ny_local
        do r = 1, fft%nz
          do p = 1, fft%nx_complex
            weight = 2.0_wp
            if (p == 1 .or. 2 * (p - 1) == fft%nx) weight = 1.0_wp
            shell = nint(sqrt(fft%wave_x(p)**2 + fft%wave_y(jj)**2 + fft%wave_z(r)**2) / stats%kappa0)
            if (shell < 1) cycle
            shell = min(shell, stats%n_shells)
            stats%spectrum(shell) = stats%spectrum(shell) + &
                0.5_wp * weight * normalisation * abs(fft%spectral_view(p, r, jj))**2
          end do
        end do
      end do
    end associate
  end subroutine add_component_spectrum
end module flow_statistics
