!> Stokes (creeping-flow) resistance of a spheroid translating and rotating in unbounded quiescent
!> fluid: the Oberbeck (1876) / Edwards (1892) / Jeffery (1922) ellipsoid solution, in the form of
!> Happel & Brenner, "Low Reynolds number hydrodynamics" (1965) sec. 5-11, and Kim & Karrila,
!> "Microhydrodynamics" (1991) sec. 3.3 (Perrin's closed forms for spheroids). For an ellipsoid
!> with semi-axes a_i and the integrals (Delta = sqrt(prod (a_j^2 + lambda)))
!>   chi = int_0^inf dlambda / Delta,  alpha_i = int_0^inf dlambda / ((a_i^2 + lambda) Delta),
!> the resistances about the principal axes are
!>   F_i = 16 pi mu U_i / (chi + a_i^2 alpha_i),
!>   T_1 = 16 pi mu (a_2^2 + a_3^2) Omega_1 / (3 (a_2^2 alpha_2 + a_3^2 alpha_3))  (and cyclic).
!> For a spheroid (a along the body x symmetry axis, b = c transverse) the integrals are closed:
!> s = sqrt(a^2 + lambda), d = b^2 - a^2:
!>   chi = (1/c) ln((a + c)/(a - c)), c^2 = a^2 - b^2 (prolate); (2/c) atan(c/a), c^2 = b^2 - a^2 (oblate)
!>   alpha_2 = alpha_3 = (chi/2 - a/b^2) / d,  alpha_1 = 2/(a b^2) - 2 alpha_2  (sum alpha_i = 2/(a b^2)).
!> Near a sphere (|d| < 0.1 a^2) the closed form cancels, so the power series in d of
!> chi = int_a^inf 2 ds/(s^2 + d) and alpha_2 = int_a^inf 2 ds/(s^2 + d)^2 is used instead.
!> Reference values (docs/physics.md sec. 4), normalised by 6 pi mu r U and 8 pi mu r^3 Omega:
!> needle (5): 1.0438, 1.3865, 0.7061, 4.6405; disk (1/5): 1.4731, 1.1279, 2.6718, 2.2398.
!> The drag is quasi-steady (no added mass, no Basset history): docs/physics.md sec. 7 explains why
!> that is the 'stokes' scene's model.
module stokes_resistance
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use spheroid, only: spheroid_t
  use rigid_body, only: rigid_body_t, angular_velocity_lab
  use quaternion, only: rotation_matrix
  implicit none
  private
  public :: stokes_resistance_t, stokes_resistance_setup, spheroid_resistance_coefficients, stokes_loads_lab, &
            stokes_loads, stokes_resistance_of, spheroid_added_mass_coefficients

  !> Drag of a rigid_body_t, or of explicit velocities and a rotation matrix.
  interface stokes_loads
    module procedure stokes_loads_body
  end interface stokes_loads

  !> Diagonal resistance tensors in the body frame (x = symmetry axis): index 1 axial, 2 and 3 transverse.
  type :: stokes_resistance_t
    real(wp) :: translational(3) = 0.0_wp   !< N s / m: F_body = -translational * U_body
    real(wp) :: rotational(3) = 0.0_wp      !< N m s: T_body = -rotational * Omega_body
    real(wp) :: dynamic_viscosity = 0.0_wp  !< mu = rho_f nu, Pa s
  end type stokes_resistance_t

contains

  !> The four normalised coefficients [F_ax, F_tr, T_ax, T_tr] of a spheroid with semi-axes a
  !> (symmetry axis) and b (transverse), divided by 6 pi mu r and 8 pi mu r^3, r^3 = a b^2.
  pure function spheroid_resistance_coefficients(axial_semi_axis, transverse_semi_axis) result(coefficients)
    real(wp), intent(in) :: axial_semi_axis, transverse_semi_axis
    real(wp) :: coefficients(4)
    real(wp) :: a, b, r, chi, alpha1, alpha2
    a = axial_semi_axis
    b = transverse_semi_axis
    r = (a * b * b)**(1.0_wp / 3.0_wp)
    call ellipsoid_integrals(a, b, chi, alpha1, alpha2)
    coefficients(1) = 16.0_wp * pi / (chi + a * a * alpha1) / (6.0_wp * pi * r)
    coefficients(2) = 16.0_wp * pi / (chi + b * b * alpha2) / (6.0_wp * pi * r)
    coefficients(3) = 16.0_wp * pi / (3.0_wp * alpha2) / (8.0_wp * pi * r**3)
    coefficients(4) = 16.0_wp * pi * (a * a + b * b) / (3.0_wp * (a * a * alpha1 + b * b * alpha2)) / (8.0_wp * pi * r**3)
  end function spheroid_resistance_coefficients

  !> Translational added-mass coefficients [k_axial, k_transverse] of a spheroid: the added mass
  !> along body axis i is k_i rho_f V. Potential flow (Lamb, "Hydrodynamics" (1932) sec. 373):
  !> k_i = alpha0_i / (2 - alpha0_i) with alpha0_i = a b^2 alpha_i, the same ellipsoid integrals as
  !> the Stokes resistance (sum_i alpha0_i = 2; a sphere has alpha0_i = 2/3, k = 1/2).
  pure function spheroid_added_mass_coefficients(axial_semi_axis, transverse_semi_axis) result(coefficients)
    real(wp), intent(in) :: axial_semi_axis, transverse_semi_axis
    real(wp) :: coefficients(2)
    real(wp) :: chi, alpha1, alpha2, alpha0(2)
    call ellipsoid_integrals(axial_semi_axis, transverse_semi_axis, chi, alpha1, alpha2)
    alpha0 = axial_semi_axis * transverse_semi_axis**2 * [alpha1, alpha2]
    coefficients = alpha0 / (2.0_wp - alpha0)
  end function spheroid_added_mass_coefficients

  !> chi, alpha_1 (axial) and alpha_2 = alpha_3 (transverse) of a spheroid.
  pure subroutine ellipsoid_integrals(a, b, chi, alpha1, alpha2)
    real(wp), intent(in) :: a, b
    real(wp), intent(out) :: chi, alpha1, alpha2
    real(wp) :: d, c, term_chi, term_alpha
    integer :: k
    d = b * b - a * a
    if (abs(d) < 0.1_wp * a * a) then
      ! chi = sum_k (-d)^k 2 / ((2k+1) a^(2k+1)), alpha_2 = sum_k (k+1) (-d)^k 2 / ((2k+3) a^(2k+3))
      chi = 0.0_wp
      alpha2 = 0.0_wp
      term_chi = 2.0_wp / a
      term_alpha = 2.0_wp / a**3
      do k = 0, 60
        chi = chi + term_chi / real(2 * k + 1, wp)
        alpha2 = alpha2 + real(k + 1, wp) * term_alpha / real(2 * k + 3, wp)
        term_chi = -term_chi * d / (a * a)
        term_alpha = -term_alpha * d / (a * a)
      end do
    else
      if (a > b) then
        c = sqrt(a * a - b * b)
        chi = log((a + c) / (a - c)) / c
      else
        c = sqrt(b * b - a * a)
        chi = 2.0_wp * atan(c / a) / c
      end if
      alpha2 = (0.5_wp * chi - a / (b * b)) / d
    end if
    alpha1 = 2.0_wp / (a * b * b) - 2.0_wp * alpha2
  end subroutine ellipsoid_integrals

  !> Dimensional resistances of a spheroid in a fluid of dynamic viscosity mu (= rho_f nu of &fluid).
  pure subroutine stokes_resistance_setup(resistance, axial_semi_axis, transverse_semi_axis, dynamic_viscosity)
    type(stokes_resistance_t), intent(out) :: resistance
    real(wp), intent(in) :: axial_semi_axis, transverse_semi_axis, dynamic_viscosity
    real(wp) :: coefficients(4), r
    coefficients = spheroid_resistance_coefficients(axial_semi_axis, transverse_semi_axis)
    r = (axial_semi_axis * transverse_semi_axis**2)**(1.0_wp / 3.0_wp)
    resistance%dynamic_viscosity = dynamic_viscosity
    resistance%translational = 6.0_wp * pi * dynamic_viscosity * r * [coefficients(1), coefficients(2), coefficients(2)]
    resistance%rotational = 8.0_wp * pi * dynamic_viscosity * r**3 * [coefficients(3), coefficients(4), coefficients(4)]
  end subroutine stokes_resistance_setup

  !> Resistances of a spheroid shape (module spheroid) in a fluid of dynamic viscosity mu = rho_f nu.
  pure function stokes_resistance_of(shape, dynamic_viscosity) result(resistance)
    type(spheroid_t), intent(in) :: shape
    real(wp), intent(in) :: dynamic_viscosity
    type(stokes_resistance_t) :: resistance
    call stokes_resistance_setup(resistance, shape%a, shape%b, dynamic_viscosity)
  end function stokes_resistance_of

  !> Lab-frame drag force and torque (about the centre) on a body in quiescent fluid.
  pure subroutine stokes_loads_body(resistance, body, force, torque)
    type(stokes_resistance_t), intent(in) :: resistance
    type(rigid_body_t), intent(in) :: body
    real(wp), intent(out) :: force(3), torque(3)
    call stokes_loads_lab(resistance, rotation_matrix(body%quaternion), body%velocity, angular_velocity_lab(body), &
                          force, torque)
  end subroutine stokes_loads_body

  !> Lab-frame drag force and torque on a spheroid with lab velocity U and lab angular velocity
  !> Omega in quiescent fluid; rotation = R(q), body -> lab: F = -R diag(zeta_t) R^T U, T likewise.
  pure subroutine stokes_loads_lab(resistance, rotation, velocity, angular_velocity, force, torque)
    type(stokes_resistance_t), intent(in) :: resistance
    real(wp), intent(in) :: rotation(3, 3), velocity(3), angular_velocity(3)
    real(wp), intent(out) :: force(3), torque(3)
    force = -matmul(rotation, resistance%translational * matmul(velocity, rotation))
    torque = -matmul(rotation, resistance%rotational * matmul(angular_velocity, rotation))
  end subroutine stokes_loads_lab
end module stokes_resistance
