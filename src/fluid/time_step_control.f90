!> The time step: fixed, or adapted to a target CFL number, never past the end time.
module time_step_control
  use agglo_kinds, only: wp
  implicit none
  private
  public :: next_time_step, explicit_viscous_limit

contains

  !> Largest stable dt of explicit (AB2) diffusion with the 7-point Laplacian: AB2 is stable on the
  !> negative real axis for lambda dt >= -1 and the most negative eigenvalue of nu L is
  !> -4 nu (1/dx^2 + 1/dy^2 + 1/dz^2), so dt <= 1 / (4 nu (1/dx^2 + 1/dy^2 + 1/dz^2)).
  pure real(wp) function explicit_viscous_limit(dx, dy, dz, viscosity)
    real(wp), intent(in) :: dx, dy, dz, viscosity
    explicit_viscous_limit = 1.0_wp / (4.0_wp * viscosity * (1.0_wp / dx**2 + 1.0_wp / dy**2 + 1.0_wp / dz**2))
  end function explicit_viscous_limit

  !> dt_mode 'fixed': dt_deck. 'cfl': min(dt_deck, cfl_target / rate, cfl_target * viscous_limit)
  !> with rate = max|u|/dx + max|v|/dy + max|w|/dz (the viscous bound only for explicit diffusion:
  !> pass huge() otherwise). The last step is shortened to end exactly at end_time.
  pure real(wp) function next_time_step(dt_mode, dt_deck, cfl_target, rate, viscous_limit, time, end_time) result(dt)
    character(len=*), intent(in) :: dt_mode
    real(wp), intent(in) :: dt_deck, cfl_target, rate, viscous_limit, time, end_time
    dt = dt_deck
    if (dt_mode == 'cfl') then
      if (rate > 0) dt = min(dt, cfl_target / rate)
      dt = min(dt, cfl_target * viscous_limit)
    end if
    ! Within a millionth of a step of the end: take the rest as the step (no sliver of a step left).
    if (time + dt * (1.0_wp + 1.0e-6_wp) >= end_time) dt = end_time - time
  end function next_time_step
end module time_step_control
