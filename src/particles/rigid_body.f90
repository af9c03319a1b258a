!> Rigid-body state and Newton-Euler update of one particle (docs/physics.md section 5; Eq. 11 of the paper).
!> Frames: position, velocity, forces and torques are in the LAB frame; the angular velocity is
!> STORED IN THE BODY FRAME (angular_velocity_body, principal axes, x = symmetry axis), where
!> Euler's equations are diagonal; angular_velocity_lab / set_angular_velocity_lab convert.
!> The quaternion (scalar first) rotates body -> lab (module quaternion).
!> Integrators (deck: &pair integrator):
!>  - 'euler' (the paper): explicit Euler of x, U, omega (Eq. 11) from the old state; the quaternion
!>    advances with the old omega (exact exponential map, so |q| = 1 to round-off). First order.
!>  - 'verlet': kick-drift-kick splitting (symplectic, second order). Kick: U += F/m h/2 and the
!>    body angular momentum L += R^T T h/2. Drift: x += U h and the torque-free rotation by the
!>    Strang splitting of the free rigid body H = sum L_k^2 / 2 I_k into exact rotations about the
!>    body axes, x(h/2) y(h/2) z(h) y(h/2) x(h/2) (Dullweber, Leimkuhler & McLachlan, J. Chem. Phys.
!>    107, 5840 (1997)); each sub-rotation keeps |L| and the lab angular momentum exactly.
!>    rigid_body_step applies both kicks with the same loads (second order for loads that are
!>    frozen over the step, e.g. hydrodynamic loads in sub-steps); a driver with position-dependent
!>    forces (DLVO) gets second order with rigid_body_kick(h/2) -> rigid_body_drift(h) ->
!>    new loads -> rigid_body_kick(h/2) (velocity Verlet).
!> Impulses in a fluid (added_inertia_t): a coupling that takes the fluid's added mass implicitly
!> moves a body under its loads with m + M_a (I + I_a), body frame. A contact or lubrication impulse
!> must then move the body with the same masses, or the contact that balances an attraction leaves
!> a net force on a held pair whose two added masses differ along the normal (docs/theory.md,
!> "Contact impulses with the added mass"). inverse_mass_lab, inverse_inertia_lab, rigid_body_kick
!> and kinetic_energy take the added masses as an option; without it they do exactly the arithmetic
!> of the body alone.
module rigid_body
  use agglo_kinds, only: wp
  use vector_algebra, only: cross, outer
  use quaternion, only: quaternion_advance, rotation_matrix, rotate_to_lab, rotate_to_body, quaternion_normalise
  use error_handling, only: fatal
  use spheroid, only: spheroid_t
  implicit none
  private
  public :: rigid_body_t, rigid_body_init, rigid_body_of_spheroid, rigid_body_step, rigid_body_kick, rigid_body_drift, &
            angular_velocity_lab, set_angular_velocity_lab, inverse_inertia_lab, point_velocity, &
            kinetic_energy, translational_kinetic_energy, rotational_kinetic_energy, linear_momentum, &
            angular_momentum, integrator_code, integrator_euler, integrator_verlet, added_inertia_t, inverse_mass_lab

  integer, parameter :: integrator_euler = 1, integrator_verlet = 2

  !> The fluid's added mass and added moments of inertia of a body along its principal axes (body
  !> frame): what an impulse moves with the body when the fluid's reaction is taken implicitly.
  type :: added_inertia_t
    real(wp) :: mass(3) = 0.0_wp       !< kg
    real(wp) :: inertia(3) = 0.0_wp    !< kg m^2
  end type added_inertia_t

  type :: rigid_body_t
    real(wp) :: mass = 0.0_wp                       !< kg
    real(wp) :: inertia_body(3) = 0.0_wp            !< kg m^2, principal moments (I_x axial, I_y, I_z)
    real(wp) :: position(3) = 0.0_wp                !< m, centre, lab frame
    real(wp) :: velocity(3) = 0.0_wp                !< m/s, centre velocity, lab frame
    real(wp) :: quaternion(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]   !< body -> lab, scalar first
    real(wp) :: angular_velocity_body(3) = 0.0_wp   !< rad/s, BODY frame
  end type rigid_body_t

contains

  !> Integrator name (deck) -> code; unknown names are a programming error (the deck check rejects them).
  integer function integrator_code(name)
    character(len=*), intent(in) :: name
    select case (trim(name))
    case ('euler'); integrator_code = integrator_euler
    case ('verlet'); integrator_code = integrator_verlet
    case default
      integrator_code = 0
      call fatal('rigid_body: unknown integrator '''//trim(name)//''' (allowed: ''euler'' | ''verlet'')')
    end select
  end function integrator_code

  !> A body with the given mass and principal moments, at rest unless velocities are given
  !> (angular velocity given in the lab frame).
  pure subroutine rigid_body_init(body, mass, inertia_body, position, quaternion, velocity, angular_velocity)
    type(rigid_body_t), intent(out) :: body
    real(wp), intent(in) :: mass, inertia_body(3), position(3), quaternion(4)
    real(wp), intent(in), optional :: velocity(3), angular_velocity(3)
    body%mass = mass
    body%inertia_body = inertia_body
    body%position = position
    body%quaternion = quaternion_normalise(quaternion)
    if (present(velocity)) body%velocity = velocity
    if (present(angular_velocity)) body%angular_velocity_body = rotate_to_body(body%quaternion, angular_velocity)
  end subroutine rigid_body_init

  !> A body with the analytic mass and inertia (Eq. 12) of a spheroid shape (module spheroid).
  pure subroutine rigid_body_of_spheroid(body, shape, position, quaternion, velocity, angular_velocity)
    type(rigid_body_t), intent(out) :: body
    type(spheroid_t), intent(in) :: shape
    real(wp), intent(in) :: position(3), quaternion(4)
    real(wp), intent(in), optional :: velocity(3), angular_velocity(3)
    call rigid_body_init(body, shape%mass, shape%inertia, position, quaternion, velocity, angular_velocity)
  end subroutine rigid_body_of_spheroid

  pure function angular_velocity_lab(body) result(omega)
    type(rigid_body_t), intent(in) :: body
    real(wp) :: omega(3)
    omega = rotate_to_lab(body%quaternion, body%angular_velocity_body)
  end function angular_velocity_lab

  pure subroutine set_angular_velocity_lab(body, omega)
    type(rigid_body_t), intent(inout) :: body
    real(wp), intent(in) :: omega(3)
    body%angular_velocity_body = rotate_to_body(body%quaternion, omega)
  end subroutine set_angular_velocity_lab

  !> Inverse lab inertia tensor i^-1 = R I^-1 R^T (i = R I R^T: paper, after Eq. 20); with added,
  !> R (I + I_a)^-1 R^T.
  pure function inverse_inertia_lab(body, added) result(inverse)
    type(rigid_body_t), intent(in) :: body
    type(added_inertia_t), intent(in), optional :: added
    real(wp) :: inverse(3, 3), r(3, 3), moments(3)
    integer :: k
    r = rotation_matrix(body%quaternion)
    moments = body%inertia_body
    if (present(added)) moments = moments + added%inertia
    inverse = 0.0_wp
    do k = 1, 3
      inverse = inverse + outer(r(:, k), r(:, k)) / moments(k)
    end do
  end function inverse_inertia_lab

  !> Inverse lab mass tensor of a body carrying its added mass, R (m + M_a)^-1 R^T.
  pure function inverse_mass_lab(body, added) result(inverse)
    type(rigid_body_t), intent(in) :: body
    type(added_inertia_t), intent(in) :: added
    real(wp) :: inverse(3, 3), r(3, 3)
    integer :: k
    r = rotation_matrix(body%quaternion)
    inverse = 0.0_wp
    do k = 1, 3
      inverse = inverse + outer(r(:, k), r(:, k)) / (body%mass + added%mass(k))
    end do
  end function inverse_mass_lab

  !> Lab velocity of the material point at lab position x: U + omega x (x - X).
  pure function point_velocity(body, point) result(u)
    type(rigid_body_t), intent(in) :: body
    real(wp), intent(in) :: point(3)
    real(wp) :: u(3)
    u = body%velocity + cross(angular_velocity_lab(body), point - body%position)
  end function point_velocity

  pure real(wp) function translational_kinetic_energy(body)
    type(rigid_body_t), intent(in) :: body
    translational_kinetic_energy = 0.5_wp * body%mass * dot_product(body%velocity, body%velocity)
  end function translational_kinetic_energy

  pure real(wp) function rotational_kinetic_energy(body)
    type(rigid_body_t), intent(in) :: body
    rotational_kinetic_energy = 0.5_wp * sum(body%inertia_body * body%angular_velocity_body**2)
  end function rotational_kinetic_energy

  !> With added: the kinetic energy of the body and of the fluid its added mass stands for,
  !> (U_b . (m + M_a) U_b + Omega_b . (I + I_a) Omega_b) / 2, body frame.
  pure real(wp) function kinetic_energy(body, added)
    type(rigid_body_t), intent(in) :: body
    type(added_inertia_t), intent(in), optional :: added
    real(wp) :: velocity_body(3)
    kinetic_energy = translational_kinetic_energy(body) + rotational_kinetic_energy(body)
    if (.not. present(added)) return
    velocity_body = rotate_to_body(body%quaternion, body%velocity)
    kinetic_energy = kinetic_energy + 0.5_wp * (sum(added%mass * velocity_body**2) &
                                                + sum(added%inertia * body%angular_velocity_body**2))
  end function kinetic_energy

  pure function linear_momentum(body) result(p)
    type(rigid_body_t), intent(in) :: body
    real(wp) :: p(3)
    p = body%mass * body%velocity
  end function linear_momentum

  !> Angular momentum about the lab origin: m X x U + R I omega_body.
  pure function angular_momentum(body) result(l)
    type(rigid_body_t), intent(in) :: body
    real(wp) :: l(3)
    l = body%mass * cross(body%position, body%velocity) &
        + rotate_to_lab(body%quaternion, body%inertia_body * body%angular_velocity_body)
  end function angular_momentum

  !> One step of length dt under lab force and torque (about the centre) held constant over the step.
  pure subroutine rigid_body_step(body, force, torque, dt, integrator)
    type(rigid_body_t), intent(inout) :: body
    real(wp), intent(in) :: force(3), torque(3), dt
    integer, intent(in) :: integrator
    real(wp) :: omega(3), torque_body(3), inertia_omega(3)
    if (integrator == integrator_verlet) then
      call rigid_body_kick(body, force, torque, 0.5_wp * dt)
      call rigid_body_drift(body, dt)
      call rigid_body_kick(body, force, torque, 0.5_wp * dt)
    else
      ! Explicit Euler (paper): every right-hand side from the old state.
      omega = body%angular_velocity_body
      torque_body = rotate_to_body(body%quaternion, torque)
      inertia_omega = body%inertia_body * omega
      body%position = body%position + dt * body%velocity
      body%velocity = body%velocity + dt * force / body%mass
      ! Eq. 11: I dw/dt = T + (I w) x w, component-wise T_x + w_y w_z (I_y - I_z), ...
      body%angular_velocity_body = omega + dt * (torque_body + cross(inertia_omega, omega)) / body%inertia_body
      body%quaternion = quaternion_advance(body%quaternion, omega, dt)
    end if
  end subroutine rigid_body_step

  !> Kick: U += F/m h and L_body += R^T T h (orientation fixed).
  pure subroutine rigid_body_kick(body, force, torque, h, added)
    type(rigid_body_t), intent(inout) :: body
    real(wp), intent(in) :: force(3), torque(3), h
    type(added_inertia_t), intent(in), optional :: added
    if (present(added)) then   ! along the principal axes, where m + M_a and I + I_a are diagonal
      body%velocity = body%velocity + rotate_to_lab(body%quaternion, &
                                                    h * rotate_to_body(body%quaternion, force) / (body%mass + added%mass))
      body%angular_velocity_body = body%angular_velocity_body &
                                   + h * rotate_to_body(body%quaternion, torque) / (body%inertia_body + added%inertia)
      return
    end if
    body%velocity = body%velocity + h * force / body%mass
    body%angular_velocity_body = body%angular_velocity_body + h * rotate_to_body(body%quaternion, torque) / body%inertia_body
  end subroutine rigid_body_kick

  !> Drift: free translation and torque-free rotation over h by the symmetric splitting
  !> x(h/2) y(h/2) z(h) y(h/2) x(h/2) of the free rigid body.
  pure subroutine rigid_body_drift(body, h)
    type(rigid_body_t), intent(inout) :: body
    real(wp), intent(in) :: h
    body%position = body%position + h * body%velocity
    call free_rotation_about_axis(body, 1, 0.5_wp * h)
    call free_rotation_about_axis(body, 2, 0.5_wp * h)
    call free_rotation_about_axis(body, 3, h)
    call free_rotation_about_axis(body, 2, 0.5_wp * h)
    call free_rotation_about_axis(body, 1, 0.5_wp * h)
  end subroutine rigid_body_drift

  !> Exact flow of H_k = L_k^2 / (2 I_k): the body turns about its axis k by theta = omega_k h,
  !> q <- q (x) (cos theta/2, sin theta/2 e_k), and the body-frame L turns by -theta about e_k
  !> (dL/dt = L x omega_k e_k), so the lab angular momentum R L is unchanged.
  pure subroutine free_rotation_about_axis(body, axis, h)
    type(rigid_body_t), intent(inout) :: body
    integer, intent(in) :: axis
    real(wp), intent(in) :: h
    real(wp) :: angle, momentum(3), c, s, axis_rate(3)
    integer :: i, j
    momentum = body%inertia_body * body%angular_velocity_body
    angle = body%angular_velocity_body(axis) * h
    axis_rate = 0.0_wp
    axis_rate(axis) = body%angular_velocity_body(axis)
    body%quaternion = quaternion_advance(body%quaternion, axis_rate, h)
    i = mod(axis, 3) + 1          ! the two other axes, cyclic (i, j) = (y, z), (z, x), (x, y)
    j = mod(axis + 1, 3) + 1
    c = cos(angle)
    s = sin(angle)
    body%angular_velocity_body(i) = (c * momentum(i) + s * momentum(j)) / body%inertia_body(i)
    body%angular_velocity_body(j) = (-s * momentum(i) + c * momentum(j)) / body%inertia_body(j)
  end subroutine free_rotation_about_axis

end module rigid_body
