!> Order statistics of small samples (benchmark repetitions, timings) and the least-squares line.
module sample_statistics
  use, intrinsic :: ieee_arithmetic, only: ieee_value, ieee_quiet_nan
  use agglo_kinds, only: wp
  implicit none
  private
  public :: median, sorted_values, linear_fit_t, linear_fit

  !> The least-squares line y = intercept + slope x and the standard errors of its two coefficients.
  !> Quantities that the points do not determine are quiet NaN: everything with fewer than two
  !> distinct x, the standard errors with fewer than three points (no residual degree of freedom).
  type :: linear_fit_t
    integer :: points = 0                  !< number of points fitted
    real(wp) :: slope = 0.0_wp
    real(wp) :: intercept = 0.0_wp
    real(wp) :: slope_error = 0.0_wp       !< standard error of the slope
    real(wp) :: intercept_error = 0.0_wp   !< standard error of the intercept
  end type linear_fit_t

contains

  !> The median (for an even count the lower of the two middle values).
  real(wp) function median(values)
    real(wp), intent(in) :: values(:)
    real(wp) :: sorted(size(values))
    sorted = sorted_values(values)
    median = sorted((size(sorted) + 1) / 2)
  end function median

  !> A copy of values in ascending order, by insertion sort: the samples are a few dozen
  !> repetitions at most.
  pure function sorted_values(values) result(sorted)
    real(wp), intent(in) :: values(:)
    real(wp) :: sorted(size(values)), held
    integer :: i, j
    sorted = values
    do i = 2, size(sorted)
      held = sorted(i); j = i - 1
      do while (j >= 1)
        if (sorted(j) <= held) exit
        sorted(j + 1) = sorted(j); j = j - 1
      end do
      sorted(j + 1) = held
    end do
  end function sorted_values

  !> Ordinary least squares of y on x (x exact, independent errors of one variance in y). With
  !> S_xx = sum (x - <x>)^2, residuals e and s^2 = sum e^2 / (n - 2):
  !> slope = sum (x - <x>)(y - <y>) / S_xx, intercept = <y> - slope <x>,
  !> se(slope) = s / sqrt(S_xx), se(intercept) = s sqrt(1/n + <x>^2 / S_xx)
  !> (e.g. Draper & Smith, Applied Regression Analysis, ch. 1). A confidence interval is
  !> slope +- t(n - 2) se(slope) with Student's t for n - 2 degrees of freedom.
  pure function linear_fit(x, y) result(fit)
    real(wp), intent(in) :: x(:), y(:)
    type(linear_fit_t) :: fit
    real(wp) :: x_mean, y_mean, sxx, sxy, residual_variance, nan
    nan = ieee_value(1.0_wp, ieee_quiet_nan)
    fit%points = size(x)
    fit%slope = nan
    fit%intercept = nan
    fit%slope_error = nan
    fit%intercept_error = nan
    if (fit%points < 2 .or. size(y) /= size(x)) return
    x_mean = sum(x) / fit%points
    y_mean = sum(y) / fit%points
    sxx = sum((x - x_mean)**2)
    if (.not. (sxx > 0.0_wp)) return
    sxy = sum((x - x_mean) * (y - y_mean))
    fit%slope = sxy / sxx
    fit%intercept = y_mean - fit%slope * x_mean
    if (fit%points < 3) return
    residual_variance = sum((y - fit%intercept - fit%slope * x)**2) / (fit%points - 2)
    fit%slope_error = sqrt(residual_variance / sxx)
    fit%intercept_error = sqrt(residual_variance * (1.0_wp / fit%points + x_mean**2 / sxx))
  end function linear_fit
end module sample_statistics
