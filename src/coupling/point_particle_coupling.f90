!> Point-particle (one-way) coupling: the hydrodynamic force and torque on each spheroid from the
!> fluid velocity at its centre, the fluid solved without the bodies (docs/theory.md, "Point
!> particles in the resolved flow"). Per body, lab frame, with u_f, Omega_f = (1/2) curl u_f and
!> Du/Dt the undisturbed flow at the centre:
!>   F = -R zeta_t R^T (U - u_f) + rho_f V Du/Dt [+ added mass],   T = -R zeta_r R^T (Omega - Omega_f),
!> zeta_t, zeta_r the 'stokes' scene's resistance tensors (stokes_resistance). rho_f V Du/Dt is the
!> force the undisturbed flow's pressure gradient and viscous stress put on the fluid volume the body
!> occupies (Maxey & Riley 1983, eq. 2.1 without the Faxen, Basset and gravity terms). The optional
!> added mass, -rho_f V K (dU/dt - Du/Dt) with the body-frame tensor K = diag(k_ax, k_tr, k_tr) of a
!> spheroid (stokes_resistance: spheroid_added_mass_coefficients), is taken implicitly: the body's
!> acceleration solves (m I + rho_f V K) dU/dt = F_other + rho_f V (I + K) Du/Dt, diagonal in the
!> body frame, and the load handed to the particle step is m dU/dt - F_dlvo, so that the explicit
!> particle step (which divides by m alone) moves the body with that acceleration. Implicit, it is
!> stable for any density ratio (a lagged -K dU/dt is not once rho_f V k > m: the face-on disk).
!> No Jeffery strain torque, no Faxen corrections, no rotational added inertia: the model of a body
!> much smaller than the flow's scales (docs/theory.md says where it stops being one).
!>
!> Time: the driver samples the fluid at the bodies' centres (the anchors) before and after each
!> fluid step (point_coupling_sample, collective); the sub-steps in between read the fluid linearly
!> interpolated in time between u^n and u^{n+1} and, around the anchor, linearly in space with the
!> interpolated gradient: u_f(x, t^n + theta dt) = (1 - theta) u^n + theta u^{n+1} + G_theta (x - anchor),
!> G_theta = (1 - theta) G^n + theta G^{n+1}, Du/Dt = (u^{n+1} - u^n) / dt + G_theta u_f.
!> Every rank holds the same samples (summed over ranks), so every rank computes the same loads.
module point_particle_coupling
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use spheroid, only: spheroid_t
  use rigid_body, only: rigid_body_t, angular_velocity_lab
  use quaternion, only: rotation_matrix, quaternion_advance
  use vector_algebra, only: cross
  use periodic_box, only: minimum_image
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_of, stokes_loads_lab, &
                               spheroid_added_mass_coefficients
  use fluid_grid, only: fluid_grid_t
  use field_interpolation, only: velocity_and_gradient_at_points, sampling_order
  implicit none
  private
  public :: point_coupling_t, point_fluid_t, point_coupling_create, point_coupling_sample, point_fluid_at, &
            point_body_loads, local_rotation, sample_velocity, sample_start, sample_end, point_free_step

  !> Which end of the fluid step a sample belongs to.
  integer, parameter :: sample_start = 1, sample_end = 2

  !> The undisturbed flow at one point and time.
  type :: point_fluid_t
    real(wp) :: velocity(3) = 0.0_wp            !< m/s
    real(wp) :: angular_velocity(3) = 0.0_wp    !< rad/s, (1/2) curl u
    real(wp) :: acceleration(3) = 0.0_wp        !< m/s^2, Du/Dt
  end type point_fluid_t

  type :: point_coupling_t
    integer :: n = 0                                  !< bodies
    type(stokes_resistance_t), allocatable :: resistance(:)   !< (n)
    real(wp), allocatable :: fluid_mass(:)            !< (n) kg, rho_f V
    real(wp), allocatable :: added_mass(:, :)         !< (3, n) kg, body frame: rho_f V [k_ax, k_tr, k_tr]
    logical :: with_added_mass = .false.
    real(wp) :: box_length(3) = 0.0_wp                !< m, the fluid's periodic box
    real(wp) :: dt = 0.0_wp                           !< s, the fluid step the samples span
    real(wp), allocatable :: anchor(:, :)             !< (3, n) m, centres where the fluid was sampled
    integer, allocatable :: visit(:)                  !< the anchors this rank samples, in cell order (sampling_order)
    real(wp), allocatable :: velocity(:, :, :)        !< (3, n, 2) m/s at the anchors, u^n and u^{n+1}
    real(wp), allocatable :: gradient(:, :, :, :)     !< (3, 3, n, 2) 1/s, d u_a / d x_b, G^n and G^{n+1}
  end type point_coupling_t

contains

  !> Coupling of bodies of the given shapes in a fluid of density rho_f (kg/m^3) and dynamic
  !> viscosity mu (Pa s) in a periodic box; the samples start at rest (zero).
  subroutine point_coupling_create(coupling, shapes, fluid_density, dynamic_viscosity, box_length, added_mass)
    type(point_coupling_t), intent(out) :: coupling
    type(spheroid_t), intent(in) :: shapes(:)
    real(wp), intent(in) :: fluid_density, dynamic_viscosity, box_length(3)
    logical, intent(in) :: added_mass
    real(wp) :: k(2)
    integer :: i
    coupling%n = size(shapes)
    allocate(coupling%resistance(coupling%n), coupling%fluid_mass(coupling%n), coupling%added_mass(3, coupling%n))
    do i = 1, coupling%n
      coupling%resistance(i) = stokes_resistance_of(shapes(i), dynamic_viscosity)
      coupling%fluid_mass(i) = fluid_density * shapes(i)%volume
      k = spheroid_added_mass_coefficients(shapes(i)%a, shapes(i)%b)
      coupling%added_mass(:, i) = coupling%fluid_mass(i) * [k(1), k(2), k(2)]
    end do
    coupling%with_added_mass = added_mass
    coupling%box_length = box_length
    allocate(coupling%anchor(3, coupling%n), coupling%velocity(3, coupling%n, 2), &
             coupling%gradient(3, 3, coupling%n, 2))
    coupling%anchor = 0.0_wp
    coupling%velocity = 0.0_wp
    coupling%gradient = 0.0_wp
  end subroutine point_coupling_create

  !> The fluid velocity and its gradient at the anchors (which = sample_start: the anchors become
  !> the bodies' current centres; sample_end: the same anchors, after the fluid step of length dt).
  !> u, v, w: the staggered velocity with current halos. Collective.
  subroutine point_coupling_sample(coupling, grid, u, v, w, bodies, which, dt)
    type(point_coupling_t), intent(inout) :: coupling
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    type(rigid_body_t), intent(in) :: bodies(:)
    integer, intent(in) :: which
    real(wp), intent(in), optional :: dt      !< s, with sample_end: the fluid step just taken
    integer :: i
    if (size(bodies) /= coupling%n) call fatal('point_coupling_sample: one body per coupled shape is required')
    if (which == sample_start) then
      do i = 1, coupling%n
        coupling%anchor(:, i) = bodies(i)%position
      end do
      ! Both samples of a fluid step are taken at these anchors: one order for the two.
      call sampling_order(grid, coupling%anchor, coupling%visit)
    else
      if (.not. present(dt)) call fatal('point_coupling_sample: the end sample needs the fluid step dt')
      if (.not. (dt > 0.0_wp)) call fatal('point_coupling_sample: the fluid step must be > 0')
      if (.not. allocated(coupling%visit)) call fatal('point_coupling_sample: the end sample needs the start sample')
      coupling%dt = dt
    end if
    call velocity_and_gradient_at_points(grid, u, v, w, coupling%anchor, coupling%velocity(:, :, which), &
                                         coupling%gradient(:, :, :, which), coupling%visit)
  end subroutine point_coupling_sample

  !> The velocity and its gradient G(a, b) = d u_a / d x_b at points (m), on every rank
  !> (collective; u, v, w with current halos): field_interpolation's trilinear value and centred
  !> gradient, which give the same result on any number of ranks, the points visited in the order
  !> of their grid cells (sampling_order).
  subroutine sample_velocity(grid, u, v, w, points, velocity, gradient)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: points(:, :)            !< (3, n)
    real(wp), intent(out) :: velocity(:, :)         !< (3, n) m/s
    real(wp), intent(out) :: gradient(:, :, :)      !< (3, 3, n) 1/s
    integer, allocatable :: visit(:)
    call sampling_order(grid, points, visit)
    call velocity_and_gradient_at_points(grid, u, v, w, points, velocity, gradient, visit)
  end subroutine sample_velocity

  !> The undisturbed flow at position (m) at the fraction theta in [0, 1] of the sampled fluid step,
  !> for body i (module header). Without an end sample (dt = 0) the start sample is frozen.
  pure function point_fluid_at(coupling, i, position, theta) result(fluid)
    type(point_coupling_t), intent(in) :: coupling
    integer, intent(in) :: i
    real(wp), intent(in) :: position(3), theta
    type(point_fluid_t) :: fluid
    real(wp) :: gradient(3, 3), offset(3), rate(3)
    if (coupling%dt > 0.0_wp) then
      gradient = (1.0_wp - theta) * coupling%gradient(:, :, i, 1) + theta * coupling%gradient(:, :, i, 2)
      fluid%velocity = (1.0_wp - theta) * coupling%velocity(:, i, 1) + theta * coupling%velocity(:, i, 2)
      rate = (coupling%velocity(:, i, 2) - coupling%velocity(:, i, 1)) / coupling%dt
    else
      gradient = coupling%gradient(:, :, i, 1)
      fluid%velocity = coupling%velocity(:, i, 1)
      rate = 0.0_wp
    end if
    ! The body may have crossed the periodic boundary since the anchor was taken.
    offset = minimum_image(position - coupling%anchor(:, i), coupling%box_length)
    fluid%velocity = fluid%velocity + matmul(gradient, offset)
    fluid%angular_velocity = local_rotation(gradient)
    ! Du/Dt = du/dt + (u . grad) u, (u . grad) u_a = G_ab u_b.
    fluid%acceleration = rate + matmul(gradient, fluid%velocity)
  end function point_fluid_at

  !> The local rotation rate (1/2) curl u (rad/s) of a velocity gradient G(a, b) = d u_a / d x_b.
  pure function local_rotation(gradient) result(rotation)
    real(wp), intent(in) :: gradient(3, 3)
    real(wp) :: rotation(3)
    rotation = 0.5_wp * [gradient(3, 2) - gradient(2, 3), gradient(1, 3) - gradient(3, 1), gradient(2, 1) - gradient(1, 2)]
  end function local_rotation

  !> Force and torque (lab frame, about the centre) on body i in the flow `fluid` (module header).
  !> other_force: the body's non-hydrodynamic force over the step (N: the DLVO load; collision
  !> impulses carry the same added mass, driver point_hydrodynamics: impulse_inertia), needed by the
  !> implicit added mass only.
  pure subroutine point_body_loads(coupling, i, body, fluid, other_force, force, torque)
    type(point_coupling_t), intent(in) :: coupling
    integer, intent(in) :: i
    type(rigid_body_t), intent(in) :: body
    type(point_fluid_t), intent(in) :: fluid
    real(wp), intent(in) :: other_force(3)
    real(wp), intent(out) :: force(3), torque(3)
    real(wp) :: rotation(3, 3), total_body(3), acceleration_body(3), fluid_acceleration_body(3)
    rotation = rotation_matrix(body%quaternion)
    call stokes_loads_lab(coupling%resistance(i), rotation, body%velocity - fluid%velocity, &
                          angular_velocity_lab(body) - fluid%angular_velocity, force, torque)
    force = force + coupling%fluid_mass(i) * fluid%acceleration
    if (.not. coupling%with_added_mass) return
    ! (m + rho_f V k_j) a_j = F_j + rho_f V k_j (Du/Dt)_j per body axis j, F = drag + rho_f V Du/Dt + other.
    total_body = matmul(force + other_force, rotation)
    fluid_acceleration_body = matmul(fluid%acceleration, rotation)
    acceleration_body = (total_body + coupling%added_mass(:, i) * fluid_acceleration_body) &
                        / (body%mass + coupling%added_mass(:, i))
    force = body%mass * matmul(rotation, acceleration_body) - other_force
  end subroutine point_body_loads

  !> Body i over the whole sampled fluid step dt in one update, for a body with no pair force
  !> (docs/theory.md, "Near-pair sub-steps"). Along each body axis j, orientation held over the step,
  !> the point particle's equation of motion (module header; no DLVO, no contact)
  !>   (m + m_a,j) dU_j/dt = -zeta_j (U_j - u_j(t)) + (rho_f V + m_a,j) (Du/Dt)_j,
  !> with the fluid seen by the body u(t) = u_m + b (t - dt/2), u_m and Du/Dt taken at the middle of
  !> the step (theta = 1/2) at the middle of the body's path and b = Du/Dt (the rate of change of the
  !> fluid velocity along a path that follows the fluid), is linear with constant coefficients; its
  !> exact solution with tau_j = (m + m_a,j) / zeta_j,
  !>   U(t) = V(t) + (U(0) - V(0)) exp(-t / tau),   V(t) = u(t) + (rho_f V + m_a) Du/Dt / zeta - b tau,
  !>   X(dt) = X(0) + (u_m + (rho_f V + m_a) Du/Dt / zeta - b tau) dt + (U(0) - V(0)) tau (1 - exp(-dt / tau)),
  !> is the exponential (integrating-factor) integrator of the linear drag, exact for any dt / tau
  !> (Hochbruck & Ostermann, Acta Numerica 19, 209, 2010; for the Stokes drag of point particles e.g.
  !> Ireland, Bragg & Collins, J. Fluid Mech. 796, 617, 2016, appendix), so stable and accurate for a
  !> Stokes response time much shorter than the step. The middle of the path is found by one
  !> predictor pass (second order in dt). The spin relaxes the same way to the fluid's rotation
  !> (1/2) curl u with tau_r,j = I_j / zeta_r,j, the gyroscopic term held at its start value; the
  !> orientation advances with the mean angular velocity over the step.
  pure subroutine point_free_step(coupling, i, body, dt)
    type(point_coupling_t), intent(in) :: coupling
    integer, intent(in) :: i
    type(rigid_body_t), intent(inout) :: body
    real(wp), intent(in) :: dt
    type(point_fluid_t) :: fluid
    real(wp) :: rotation(3, 3), mass(3), carried(3), tau(3), relax(3), start_velocity(3), rate(3), target(3)
    real(wp) :: midpoint(3), travel(3), spin0(3), spin_target(3), tau_r(3), relax_r(3), spin_mean(3)
    integer :: pass
    rotation = rotation_matrix(body%quaternion)
    mass = body%mass
    carried = coupling%fluid_mass(i)
    if (coupling%with_added_mass) then
      mass = mass + coupling%added_mass(:, i)
      carried = carried + coupling%added_mass(:, i)
    end if
    tau = mass / coupling%resistance(i)%translational
    relax = one_minus_exp(dt / tau)
    start_velocity = matmul(body%velocity, rotation)
    midpoint = body%position + 0.5_wp * dt * body%velocity
    do pass = 1, 2
      fluid = point_fluid_at(coupling, i, midpoint, 0.5_wp)
      rate = matmul(fluid%acceleration, rotation)
      ! V at the middle of the step; V(0) = target - b dt / 2.
      target = matmul(fluid%velocity, rotation) + carried * rate / coupling%resistance(i)%translational - rate * tau
      travel = target * dt + (start_velocity - (target - 0.5_wp * dt * rate)) * tau * relax
      midpoint = body%position + 0.5_wp * matmul(rotation, travel)
    end do
    body%position = body%position + matmul(rotation, travel)
    body%velocity = matmul(rotation, target + 0.5_wp * dt * rate &
                                     + (start_velocity - (target - 0.5_wp * dt * rate)) * (1.0_wp - relax))
    spin0 = body%angular_velocity_body
    tau_r = body%inertia_body / coupling%resistance(i)%rotational
    relax_r = one_minus_exp(dt / tau_r)
    spin_target = matmul(fluid%angular_velocity, rotation) &
                  + cross(body%inertia_body * spin0, spin0) / coupling%resistance(i)%rotational
    spin_mean = spin_target + (spin0 - spin_target) * tau_r * relax_r / dt
    body%angular_velocity_body = spin_target + (spin0 - spin_target) * (1.0_wp - relax_r)
    body%quaternion = quaternion_advance(body%quaternion, spin_mean, dt)
  end subroutine point_free_step

  !> 1 - exp(-h) for h >= 0, without the cancellation of small h (its Taylor series there).
  elemental real(wp) function one_minus_exp(h)
    real(wp), intent(in) :: h
    if (h < 1.0e-4_wp) then
      one_minus_exp = h * (1.0_wp - h * (0.5_wp - h * (1.0_wp / 6.0_wp - h / 24.0_wp)))
    else
      one_minus_exp = 1.0_wp - exp(-h)
    end if
  end function one_minus_exp
end module point_particle_coupling
