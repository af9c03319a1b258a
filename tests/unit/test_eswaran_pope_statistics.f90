! checks: 20
!> Statistics of the Ornstein-Uhlenbeck coefficients of eswaran_pope_forcing, for both update forms.
!> Theory (paper Eqs. 5-6; docs/physics.md section 3): every real and imaginary part of every component
!> is an independent OU process with mean 0, variance sigma^2 and autocorrelation
!> sigma^2 exp(-s/T_L). Each process gives one estimate of each statistic from its time series;
!> the processes are independent, so the standard error of the average estimate is the spread of
!> the per-process estimates over sqrt(number of processes). Checks: within 4 standard errors.
!> Euler-Maruyama (paper Eq. 3) is a discretisation of the OU process: its stationary variance is
!> sigma^2 / (1 - h/2) and its lag-m autocorrelation (1 - h)^m, h = dt/T_L. At h = 0.002 this bias
!> (0.1%) is a quarter of a standard error, so it is checked against the continuous theory there;
!> at h = 0.5 it is checked against its own discrete theory (and the exact form, exact for any dt,
!> against the continuous one), which shows the checks resolve a wrong variance.
program test_eswaran_pope_statistics
  use agglo_kinds, only: wp
  use config_forcing, only: forcing_config_t
  use eswaran_pope_forcing, only: ep_forcing_t, forcing_init, forcing_advance, forcing_coefficients, &
                                  forcing_pair_count
  use parallel_env, only: parallel_start
  use test_framework, only: test_start, test_finish, check_close
  implicit none

  real(wp), parameter :: sigma = 1.3_wp, time_scale = 0.01_wp

  call parallel_start()
  call test_start('eswaran_pope_statistics')
  ! exact update, h = 0.05: lags T_L/2 and T_L are 10 and 20 steps.
  call ou_statistics('exact', 0.05_wp, 8, 200.0_wp, 1.0_wp, exp(-0.5_wp), exp(-1.0_wp), 'exact_h0.05', 1000)
  ! Euler-Maruyama, h = 0.002: lags of 250 and 500 steps; continuous theory (bias 0.1% << SE).
  call ou_statistics('euler_maruyama', 0.002_wp, 4, 200.0_wp, 1.0_wp, exp(-0.5_wp), exp(-1.0_wp), 'em_h0.002', 2000)
  ! Large steps: exact still exact; Euler-Maruyama follows its discrete theory.
  call ou_statistics('exact', 0.5_wp, 8, 400.0_wp, 1.0_wp, exp(-0.5_wp), exp(-1.0_wp), 'exact_h0.5', 3000)
  call ou_statistics('euler_maruyama', 0.5_wp, 8, 400.0_wp, 1.0_wp / 0.75_wp, 0.5_wp / 0.75_wp, &
                     0.25_wp / 0.75_wp, 'em_h0.5_discrete_theory', 4000)
  call test_finish()

contains

  !> Run instances forcings (independent seeds seed_base + 1, ...) for duration T_L at dt = h T_L and check the mean,
  !> variance and the autocovariance at lags T_L/2 and T_L against sigma^2 times the given
  !> normalised values, and the covariance of the real and imaginary parts against 0.
  subroutine ou_statistics(update, h, instances, duration, variance_ratio, lag_half_ratio, lag_full_ratio, label, seed_base)
    character(len=*), intent(in) :: update, label
    real(wp), intent(in) :: h, duration, variance_ratio, lag_half_ratio, lag_full_ratio
    integer, intent(in) :: instances, seed_base
    type(forcing_config_t) :: cfg
    type(ep_forcing_t), allocatable :: forcing(:)
    real(wp), allocatable :: history(:,:), x(:), sum_x(:), sum_xx(:), sum_half(:), sum_full(:), sum_re_im(:)
    complex(wp), allocatable :: b(:,:)
    integer :: lag_half, lag_full, steps, step, p, per_instance, n, pairs, slot
    cfg%time_scale = time_scale
    cfg%sigma = sigma
    cfg%update = update
    allocate(forcing(instances))
    do n = 1, instances
      call forcing_init(forcing(n), cfg, seed_base + n, [8, 8, 8], [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], 8, 0)
    end do
    pairs = forcing_pair_count(forcing(1))
    per_instance = 6 * pairs
    p = per_instance * instances
    lag_half = nint(0.5_wp / h)
    lag_full = nint(1.0_wp / h)
    steps = nint(duration / h)
    allocate(history(p, 0:lag_full), x(p))
    allocate(sum_x(p), sum_xx(p), sum_half(p), sum_full(p), sum_re_im(p / 2), source=0.0_wp)
    do step = 0, steps - 1
      if (step > 0) then
        do n = 1, instances
          call forcing_advance(forcing(n), h * time_scale)
        end do
      end if
      do n = 1, instances
        b = forcing_coefficients(forcing(n))
        ! Layout: for each mode and component, the real part then the imaginary part.
        x((n - 1) * per_instance + 1:n * per_instance:2) = reshape(real(b, wp), [3 * pairs])
        x((n - 1) * per_instance + 2:n * per_instance:2) = reshape(aimag(b), [3 * pairs])
      end do
      slot = modulo(step, lag_full + 1)
      history(:, slot) = x
      sum_x = sum_x + x
      sum_xx = sum_xx + x**2
      sum_re_im = sum_re_im + x(1::2) * x(2::2)
      if (step >= lag_half) sum_half = sum_half + x * history(:, modulo(step - lag_half, lag_full + 1))
      if (step >= lag_full) sum_full = sum_full + x * history(:, modulo(step - lag_full, lag_full + 1))
    end do
    call check_mean_of_estimates(sum_x / steps, 0.0_wp, label//'_mean')
    call check_mean_of_estimates(sum_xx / steps, sigma**2 * variance_ratio, label//'_variance')
    call check_mean_of_estimates(sum_half / (steps - lag_half), sigma**2 * lag_half_ratio, label//'_autocov_T_L/2')
    call check_mean_of_estimates(sum_full / (steps - lag_full), sigma**2 * lag_full_ratio, label//'_autocov_T_L')
    call check_mean_of_estimates(sum_re_im / steps, 0.0_wp, label//'_re_im_uncorrelated')
  end subroutine ou_statistics

  !> The average of independent per-process estimates against theory, within 4 standard errors.
  subroutine check_mean_of_estimates(estimates, expected, name)
    real(wp), intent(in) :: estimates(:), expected
    character(len=*), intent(in) :: name
    real(wp) :: average, standard_error
    average = sum(estimates) / size(estimates)
    standard_error = sqrt(sum((estimates - average)**2) / (size(estimates) - 1) / size(estimates))
    call check_close(average, expected, 0.0_wp, name, abs_tol=4.0_wp * standard_error)
  end subroutine check_mean_of_estimates
end program test_eswaran_pope_statistics
