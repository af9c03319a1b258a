!> Unsteady Stokes drag of a sphere released with a velocity in fluid at rest: the reference of
!> docs/studies/validation.md, "Free particles" (the release decay; docs/theory.md, "A sphere released in
!> fluid at rest"). The Basset-Boussinesq-Oseen equation in the form of Maxey & Riley (1983, Phys.
!> Fluids 26, 883, no gravity, the fluid at rest far away), for t > 0:
!>   (m + m_f/2) dU/dt = -6 pi mu a U - 6 a^2 sqrt(pi rho_f mu) [U(0+)/sqrt(t) + int_0^t (dU/dtau) / sqrt(t - tau) dtau],
!> m_f = rho_f 4/3 pi a^3; the term U(0+)/sqrt(t) is the history of the start, the relative
!> velocity jumping from 0 to U(0+) (Michaelides 1997, J. Fluids Eng. 119, 233). Integrated
!> once in time (the bracket is d/dt int_0^t U(tau)/sqrt(t - tau) dtau) it is a Volterra equation of
!> the second kind with a weakly singular kernel,
!>   U(t) = U(0+) - beta int_0^t U dtau - gamma int_0^t U(tau)/sqrt(t - tau) dtau,
!>   beta = 6 pi mu a / (m + m_f/2),   gamma = 6 a^2 sqrt(pi rho_f mu) / (m + m_f/2),
!> solved by product integration (release_decay_quadrature): U piecewise linear between the nodes,
!> the kernel 1/sqrt(t - tau) integrated exactly against it, the ordinary integral by the trapezoid
!> rule; implicit in the newest node. Its Laplace transform is closed,
!>   U~(s) = U(0+) / (s + gamma sqrt(pi) sqrt(s) + beta)
!> (Basset 1888, "A treatise on hydrodynamics" vol. 2 ch. 22; Michaelides 1997), and inverted
!> numerically on Talbot's contour as the cross-check (release_decay_laplace).
!>
!> A body released at U_0 in fluid at rest (the fluid outside without motion) is not yet an
!> incompressible state: the impulsive pressure that sets up the potential flow takes the added
!> mass's momentum from the body, so m U_0 = (m + m_f/2) U(0+) (the impulse of the potential flow,
!> Lamb 1932, "Hydrodynamics" ch. VI), released_start_velocity.
module unsteady_stokes
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  implicit none
  private
  public :: released_sphere_t, released_start_velocity, release_decay_quadrature, release_decay_laplace, &
            particle_response_time

  !> The sphere and the fluid (SI).
  type :: released_sphere_t
    real(wp) :: radius = 0             !< m, a
    real(wp) :: density = 0            !< kg/m^3, rho_p
    real(wp) :: fluid_density = 0      !< kg/m^3, rho_f
    real(wp) :: viscosity = 0          !< Pa s, mu
  end type released_sphere_t

contains

  !> tau_p = 2 rho_p a^2 / (9 mu), the particle response time (s).
  pure real(wp) function particle_response_time(sphere) result(tau)
    type(released_sphere_t), intent(in) :: sphere
    tau = 2.0_wp * sphere%density * sphere%radius**2 / (9.0_wp * sphere%viscosity)
  end function particle_response_time

  !> U(0+) of a sphere released at start_velocity in fluid at rest: m U_0 / (m + m_f/2).
  pure real(wp) function released_start_velocity(sphere, start_velocity) result(velocity)
    type(released_sphere_t), intent(in) :: sphere
    real(wp), intent(in) :: start_velocity
    velocity = start_velocity * sphere%density / (sphere%density + 0.5_wp * sphere%fluid_density)
  end function released_start_velocity

  !> The equation's two rates (module header): beta (1/s) and gamma (1/sqrt(s)).
  pure subroutine decay_rates(sphere, beta, gamma)
    type(released_sphere_t), intent(in) :: sphere
    real(wp), intent(out) :: beta, gamma
    real(wp) :: effective_mass
    effective_mass = (sphere%density + 0.5_wp * sphere%fluid_density) * 4.0_wp * pi * sphere%radius**3 / 3.0_wp
    beta = 6.0_wp * pi * sphere%viscosity * sphere%radius / effective_mass
    gamma = 6.0_wp * sphere%radius**2 * sqrt(pi * sphere%fluid_density * sphere%viscosity) / effective_mass
  end subroutine decay_rates

  !> U(n h) / U(0+), n = 0 .. size(velocity) - 1, by product integration with the step h (s)
  !> (module header). Cost O(n^2). The error falls as h^(3/2) (U - U(0+) grows as sqrt(t)).
  pure subroutine release_decay_quadrature(sphere, step, velocity)
    type(released_sphere_t), intent(in) :: sphere
    real(wp), intent(in) :: step
    real(wp), intent(out) :: velocity(0:)
    real(wp) :: beta, gamma, root_step, diagonal, history, running_sum
    real(wp), allocatable :: lower(:), upper(:)
    integer :: n, j, last, k
    call decay_rates(sphere, beta, gamma)
    last = ubound(velocity, 1)
    ! Over [t_j, t_j+1] with sigma = (t_n - tau)/h in [k, k + 1], k = n - j - 1: the weight of U_j is
    ! int (sigma - k) sigma^(-1/2), of U_j+1 int (k + 1 - sigma) sigma^(-1/2).
    allocate(lower(0:max(last - 1, 0)), upper(0:max(last - 1, 0)))
    do k = 0, last - 1
      associate (i0 => 2.0_wp * (sqrt(real(k + 1, wp)) - sqrt(real(k, wp))), &
                 i1 => 2.0_wp / 3.0_wp * (real(k + 1, wp)**1.5_wp - real(k, wp)**1.5_wp))
        lower(k) = i1 - k * i0
        upper(k) = (k + 1) * i0 - i1
      end associate
    end do
    root_step = sqrt(step)
    velocity(0) = 1.0_wp
    running_sum = 0.5_wp * velocity(0)
    do n = 1, last
      history = 0.0_wp
      do j = 0, n - 1
        history = history + velocity(j) * lower(n - j - 1)
      end do
      do j = 0, n - 2
        history = history + velocity(j + 1) * upper(n - j - 1)
      end do
      diagonal = 1.0_wp + 0.5_wp * beta * step + gamma * root_step * upper(0)
      velocity(n) = (1.0_wp - beta * step * running_sum - gamma * root_step * history) / diagonal
      running_sum = running_sum + velocity(n)
    end do
  end subroutine release_decay_quadrature

  !> U(t) / U(0+) from the Laplace transform (module header) on Talbot's fixed contour (Abate &
  !> Valko 2004, Int. J. Numer. Meth. Eng. 60, 979) with terms nodes; t > 0.
  pure real(wp) function release_decay_laplace(sphere, time, terms) result(velocity)
    type(released_sphere_t), intent(in) :: sphere
    real(wp), intent(in) :: time
    integer, intent(in) :: terms
    real(wp) :: beta, gamma, r, theta, cot, sigma
    complex(wp) :: s
    integer :: k
    if (.not. time > 0.0_wp) then
      velocity = 1.0_wp
      return
    end if
    call decay_rates(sphere, beta, gamma)
    r = 2.0_wp * terms / (5.0_wp * time)
    velocity = 0.5_wp * exp(r * time) * real(transform(cmplx(r, 0.0_wp, wp)))
    do k = 1, terms - 1
      theta = k * pi / terms
      cot = cos(theta) / sin(theta)
      s = r * theta * cmplx(cot, 1.0_wp, wp)
      sigma = theta + (theta * cot - 1.0_wp) * cot
      velocity = velocity + real(exp(time * s) * transform(s) * cmplx(1.0_wp, sigma, wp))
    end do
    velocity = velocity * r / terms

  contains

    !> U~(s) / U(0+), the principal square root (its cut along the negative axis, which the contour encloses).
    pure complex(wp) function transform(s)
      complex(wp), intent(in) :: s
      transform = 1.0_wp / (s + gamma * sqrt(pi) * sqrt(s) + beta)
    end function transform
  end function release_decay_laplace
end module unsteady_stokes
