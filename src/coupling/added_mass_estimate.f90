!> The added-mass stabilisation's estimate of the fluid's reaction to a velocity change of a free body
!> whose loads lag one fluid step (the provider resolved_hydrodynamics, module header "Added mass",
!> "Long fluid steps", "History with explicit diffusion"; docs/theory.md, "Free particles"): per
!> body axis, the potential-flow added mass, the quasi-steady drag over the step and the history
!> (Basset) reaction with the weights w_j = sqrt(j + 1) - sqrt(j) of a velocity step j steps back
!> (Basset 1888; Maxey & Riley 1983).
module added_mass_estimate
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  implicit none
  private
  public :: lagged_reaction, put_back

contains

  !> The lagged reaction's estimate per body axis (kg, or kg m^2 for rotation; module header):
  !> the impulse / velocity change of a body whose velocity steps at the start of a fluid step,
  !> integrated over the step, M + C dt + C L 2 sqrt(dt / (pi nu)): potential flow, quasi-steady
  !> drag and the history (Basset) reaction C L / sqrt(pi nu t), the last also returned as history.
  !> With the viscous reaction trailing by lag > 0 steps (explicit diffusion) the drag stays with the
  !> resolved load: taken implicitly it would move momentum the fluid delivers lag steps later.
  pure subroutine lagged_reaction(added, resistance, length, dt, viscosity, lag, reaction, history)
    real(wp), intent(in) :: added(3), resistance(3), length(3), dt, viscosity
    integer, intent(in) :: lag
    real(wp), intent(out) :: reaction(3), history(3)
    history = 0
    if (dt > 0.0_wp .and. viscosity > 0.0_wp) history = resistance * 2.0_wp * length * sqrt(dt / (pi * viscosity))
    reaction = added + history
    if (lag == 0) reaction = reaction + resistance * dt
  end subroutine lagged_reaction

  !> The estimate put back into the lagged load (body frame): the reaction the last step's velocity
  !> change A^n caused, less what the history reaction of each change still holds in the next step
  !> (the Basset weights w_j = sqrt(j + 1) - sqrt(j) of a velocity step j steps back), over the
  !> N = history_steps steps remembered. The resolved history reaction to a change j steps back is
  !> h_j = w_{j - lag} (zero for j < lag: explicit diffusion first sees a change in the step after it),
  !> the estimate's g_j = w_j, taken implicitly at j = 0; what the next step needs explicitly is g_{j+1}:
  !>   (lagged - history) A^n + history [sum_{j=0}^{N} (h_j - g_{j+1}) A^{n-j} + (h_s - g_s) A_start],
  !> lag 0 (Crank-Nicolson): lagged A^n - history [w_1 A^n - sum_{j=1}^{N-1} (w_j - w_{j+1}) A^{n-j} - w_N A^{n-N}].
  !> The start (lag > 0 only; its records are zero otherwise), s = since_start - 1 steps back: the
  !> jump from the fluid at rest A_start, whose implicit part was never taken (the resolved load
  !> holds its added mass), with the weights h_s - g_s (-1 at the first step, summing to zero), and
  !> the change of the second step, A_first, with those of a change s - 1 steps back, kept for the
  !> whole run: the start's changes are the largest, and leaving the memory with their remaining
  !> weight at once they would jump the velocity (1.3% of U_0 at the density ratio 1).
  pure function put_back(lagged, history, current, earlier, rotation, lag, start, first, since_start) result(estimate)
    real(wp), intent(in) :: lagged(3), history(3), current(3), earlier(:, :), rotation(3, 3), start(3), first(3)
    integer, intent(in) :: lag, since_start
    real(wp) :: estimate(3), past(3)
    integer :: j, last
    last = size(earlier, 2)
    past = history_weight(0, lag, last) * current
    do j = 1, last
      past = past + history_weight(j, lag, last) * earlier(:, j)
    end do
    if (since_start >= 1) past = past + (resolved_weight(since_start - 1, lag) - basset_weight(since_start - 1)) * start
    if (since_start >= 2) past = past + (resolved_weight(since_start - 2, lag) - basset_weight(since_start - 1)) * first
    estimate = (lagged - history) * matmul(current, rotation) + history * matmul(past, rotation)
    if (since_start == 2) estimate = estimate + (lagged - history) * matmul(first, rotation)
  end function put_back

  !> h_j - g_{j+1} of put_back; the change that leaves the memory (j = last) takes its remaining
  !> weight along, sqrt(last + 1) - sqrt(last - lag), so that the weights put back sum to lagged, the
  !> velocity changes telescope and the box's momentum budget closes.
  pure real(wp) function history_weight(j, lag, last) result(weight)
    integer, intent(in) :: j, lag, last
    if (j == last) then
      weight = sqrt(real(last + 1, wp)) - sqrt(real(last - lag, wp))
    else
      weight = resolved_weight(j, lag) - basset_weight(j + 1)
    end if
  end function history_weight

  !> h_j: the resolved history reaction j steps after a change, trailing by lag steps.
  pure real(wp) function resolved_weight(j, lag) result(weight)
    integer, intent(in) :: j, lag
    weight = 0
    if (j >= lag) weight = basset_weight(j - lag)
  end function resolved_weight

  pure real(wp) function basset_weight(j)
    integer, intent(in) :: j
    basset_weight = sqrt(real(j + 1, wp)) - sqrt(real(j, wp))
  end function basset_weight
end module added_mass_estimate
