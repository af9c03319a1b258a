! ranks: 2
! checks: 18
!> Tests of flow_statistics on a field with known statistics, on 2 ranks (the FFT and the sums
!> cross the slab boundary): u = U0 + A sin(2 pi y/L), v = B cos(6 pi z/L), w = C sin(4 pi x/L),
!> each component sampled at its own MAC faces (divergence free: each depends only on a
!> transverse coordinate). References (the definitions in flow_statistics):
!>   u'_c^2 = A^2/2, B^2/2, C^2/2 (mean U0 removed); k_E = (A^2 + B^2 + C^2)/4;
!>   epsilon = nu sum_c (amplitude_c^2 / 2) k~_c^2 with the forward-difference wavenumber
!>     k~ = 2 sin(k h/2)/h (exact for sampled sines);
!>   shell energies: s = 1: A^2/4, s = 2: C^2/4, s = 3: B^2/4, nothing elsewhere (Parseval);
!>   lambda, Re_lambda, eta, L_int from their formulas with these values.
program test_flow_statistics
  use agglo_kinds, only: wp
  use physical_constants, only: pi, two_pi
  use parallel_env, only: parallel_start
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use flow_statistics, only: flow_statistics_t, compute_flow_statistics
  use test_framework, only: test_start, test_finish, check_close, check_below
  implicit none
  type(fluid_solver_t) :: solver
  type(flow_statistics_t) :: stats
  integer, parameter :: n = 16
  real(wp), parameter :: length = 1.0e-3_wp, nu = 1.0e-6_wp
  real(wp), parameter :: u0 = 3.0e-3_wp, a = 2.0e-3_wp, b = 1.0e-3_wp, c = 1.5e-3_wp
  real(wp) :: h, kappa0, u_prime_squared, epsilon_expected, lambda, shell(3), integral
  integer :: i, j, k, kg

  call parallel_start()
  call test_start('flow_statistics')
  call fluid_solver_create(solver, grid_config_t(nx=n, ny=n, nz=n, length_x=length, length_y=length, length_z=length), &
                           fluid_config_t(viscosity=nu))
  h = length / n
  kappa0 = two_pi / length
  do k = 1, solver%grid%nz_local
    kg = solver%grid%z_offset + k
    do j = 1, n
      do i = 1, n
        solver%u(i, j, k) = u0 + a * sin(kappa0 * (j - 0.5_wp) * h)
        solver%v(i, j, k) = b * cos(3 * kappa0 * kg * h)
        solver%w(i, j, k) = c * sin(2 * kappa0 * (i - 0.5_wp) * h)
      end do
    end do
  end do
  call compute_flow_statistics(stats, solver, power_input=1.0e-3_wp)

  call check_close(stats%mean_velocity(1), u0, 1.0e-12_wp, 'mean_u')
  call check_close(stats%u_rms_component(1), a / sqrt(2.0_wp), 1.0e-12_wp, 'u_rms_x_mean_removed')
  call check_close(stats%u_rms_component(2), b / sqrt(2.0_wp), 1.0e-12_wp, 'u_rms_y')
  call check_close(stats%u_rms_component(3), c / sqrt(2.0_wp), 1.0e-12_wp, 'u_rms_z')
  u_prime_squared = (a**2 + b**2 + c**2) / 6.0_wp
  call check_close(stats%u_rms, sqrt(u_prime_squared), 1.0e-12_wp, 'u_rms')
  call check_close(stats%kinetic_energy, (a**2 + b**2 + c**2) / 4.0_wp, 1.0e-12_wp, 'kinetic_energy')
  epsilon_expected = nu * (a**2 / 2 * forward_wavenumber(1) ** 2 + b**2 / 2 * forward_wavenumber(3)**2 + &
                           c**2 / 2 * forward_wavenumber(2)**2)
  call check_close(stats%dissipation, epsilon_expected, 1.0e-12_wp, 'dissipation_forward_differences')
  call check_close(stats%power_input, 1.0e-3_wp, 0.0_wp, 'power_input_passed_through')
  lambda = sqrt(15 * nu * u_prime_squared / epsilon_expected)
  call check_close(stats%taylor_microscale, lambda, 1.0e-12_wp, 'taylor_microscale')
  call check_close(stats%re_lambda, sqrt(u_prime_squared) * lambda / nu, 1.0e-12_wp, 're_lambda')
  call check_close(stats%kolmogorov_length, (nu**3 / epsilon_expected)**0.25_wp, 1.0e-12_wp, 'kolmogorov_length')
  call check_close(stats%kmax_eta, pi / h * (nu**3 / epsilon_expected)**0.25_wp, 1.0e-12_wp, 'kmax_eta')
  shell = [a**2, c**2, b**2] / 4.0_wp
  call check_close(stats%spectrum(1) * kappa0, shell(1), 1.0e-12_wp, 'spectrum_shell_1')
  call check_close(stats%spectrum(2) * kappa0, shell(2), 1.0e-12_wp, 'spectrum_shell_2')
  call check_close(stats%spectrum(3) * kappa0, shell(3), 1.0e-12_wp, 'spectrum_shell_3')
  call check_below(maxval(abs(stats%spectrum(4:))) * kappa0, 1.0e-14_wp * sum(shell), 'spectrum_empty_elsewhere')
  call check_close(stats%spectrum_energy, stats%kinetic_energy, 1.0e-12_wp, 'spectrum_parseval')
  integral = pi / (2 * u_prime_squared) * sum(shell / ([1, 2, 3] * kappa0))
  call check_close(stats%integral_length, integral, 1.0e-12_wp, 'integral_length')
  call test_finish()

contains

  !> 2 sin(k h / 2) / h for the mode s kappa0: the forward-difference wavenumber of a sampled sine.
  real(wp) function forward_wavenumber(s)
    integer, intent(in) :: s
    forward_wavenumber = 2.0_wp * sin(s * kappa0 * h / 2.0_wp) / h
  end function forward_wavenumber
end program test_flow_statistics
