!> Sub-grid normal lubrication between two rigid spheroids (docs/theory.md, "Sub-grid lubrication";
!> issue: &collision lubrication, off by default because the paper has none).
!>
!> Squeeze-film force along the common normal n (1 -> 2) at the closest points, for a surface gap h
!> and a relative normal velocity v_n = (u1(x_c) - u2(x_c)).n (> 0 approaching):
!>   F_2 = +R_sub(h) v_n n on body 2, -F_2 on body 1, applied at x_c = (x1 + x2)/2,
!> with the resistance (N s/m) of the two surfaces near contact,
!>   R(h) = 6 pi mu [ R_eff^2 / h + a1 ( g2(l) ln(1/xi) + g3(l) xi ln(1/xi) ) ],  xi = 2 h / (a1 + a2),
!> the near-contact expansion of the axisymmetric squeeze resistance of two spheres of radii a1, a2
!> (l = a2/a1; g1 = 2 l^2/(1+l)^3, g2 = l (1 + 7 l + l^2) / (5 (1+l)^3),
!> g3 = (1 + 18 l - 29 l^2 + 18 l^3 + l^4) / (42 (1+l)^3): Jeffrey & Onishi 1984, J. Fluid Mech.
!> 139, 261, function X^A; Kim & Karrila 1991, Microhydrodynamics, ch. 11), whose leading term
!> 6 pi mu a1 g1 / xi is 6 pi mu R_eff^2 / h with R_eff = a1 a2 / (a1 + a2).
!> Curved surfaces (spheroids): the gap near the closest points is h + x^T K x / 2 with K = K1 + K2
!> the sum of the two curvature tensors on the common tangent plane. The Reynolds equation
!> div(h^3 grad p) = 12 mu v_n is then solved exactly by p = 6 mu v_n / (tr K h(x)^2), whose integral
!> gives F = 12 pi mu v_n / (h tr K sqrt(det K)), i.e.
!>   R_eff^2 = 2 / (tr K sqrt(det K))      (= (a1 a2 / (a1 + a2))^2 for spheres).
!> The logarithmic terms use the equivalent sphere radii a_i = 2 / tr K_i (mean radius of curvature of
!> surface i at its closest point; exact for spheres, an approximation for spheroids).
!>
!> Hand-over (Costa, Boersma, Westerweel & Breugem 2015, Phys. Rev. E 92, 053012: lambda(eps) -
!> lambda(eps_out)): the grid resolves the squeeze flow down to the gap h_out, so only the unresolved part is added,
!>   R_sub(h) = max(0, R(max(h, h_in)) - max(0, R(h_out)))  for h < h_out,   0 for h >= h_out,
!> saturated below the roughness gap h_in (Costa et al.: the force stays finite at contact). The
!> expansion R turns negative where the gap reaches the radii of curvature (xi > 1.71 for equal
!> spheres), which a particle-scale h_out (no resolved squeeze flow: the 'stokes' and point rungs)
!> or a sharp tip can reach: there the model subtracts nothing and never pulls.
!>
!> Time integration: R_sub can be far stiffer than the particle step (R dt / m > 2 at nanometre gaps),
!> so the pair's normal velocity is damped implicitly over dt: the impulse J = j n on body 2 (-J on
!> body 1) with j = R_sub dt v_n' and v_n' = v_n - (n^T K_c n) j (K_c the contact matrix of the
!> collision module, inverse masses and inertias at x_c), i.e. j = R_sub dt v_n / (1 + R_sub dt n^T K_c n).
!> The force reported is j n / dt. Linear and angular momentum are conserved exactly; the kinetic
!> energy never grows (the impulse only damps v_n). With the bodies' added masses (module
!> collision) K_c and the kick carry them as a collision does.
!>
!> Tangential and rotational modes (model%tangential, &collision lubrication_tangential): the
!> log(1/xi) terms of the shear and rotation resistances of two spheres near contact (Jeffrey &
!> Onishi 1984, functions Y^A, Y^B, Y^C; Kim & Karrila 1991, ch. 11). For equal spheres of radius a
!> they are exactly a force against the slip s_t (the tangential part of u1(x_c) - u2(x_c), the two
!> surfaces' relative velocity at the gap) plus a torque against the tangential relative rotation
!> (omega1 - omega2)_t:
!>   F_2 = +R_s(h) s_t (-F_2 on body 1, at x_c),  R_s = 6 pi mu a1 g_YA(l) L(h),
!>   T_2 = +R_r(h) (omega1 - omega2)_t = -T_1,       R_r = (3/5) pi mu a_r^3 L(h),
!> with g_YA = (4/15) l (2 + l + 2 l^2) / (1 + l)^3 (1/6 for equal spheres), L the sub-grid part of
!> ln(1/xi) (hand-over and roughness as for R_sub), a_r = 2 a1 a2 / (a1 + a2). For equal spheres
!> they reproduce Y^A_11 = -Y^A_12 = 1/6, Y^B_11 = 1/4, Y^C_11 = 1/5 and Y^C_12 = 1/20
!> (Jeffrey & Onishi's normalisations) exactly; R_s is exact for the relative translation of
!> unequal spheres, the rotation couplings of unequal radii (and of spheroids, through their mean
!> radii of curvature) are approximated by the equal-sphere form. Each is applied as an implicit
!> impulse along its own direction (damping only; momentum and angular momentum conserved).
module lubrication
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use vector_algebra, only: cross
  use quaternion, only: rotation_matrix
  use spheroid, only: spheroid_t, principal_curvatures, principal_directions
  use rigid_body, only: rigid_body_t, added_inertia_t, point_velocity, inverse_inertia_lab, inverse_mass_lab, &
                        rigid_body_kick, angular_velocity_lab
  use closest_points, only: closest_points_t
  use collision, only: contact_matrix, isotropic_inverse_mass
  use config_collision, only: collision_config_t
  use logger, only: log_line
  implicit none
  private
  public :: lubrication_setup, lubrication_model_t, lubrication_geometry_t, lubrication_result_t, lubrication_geometry, &
            lubrication_resistance, lubrication_subgrid_resistance, lubrication_tangential_resistances, lubricate

  type :: lubrication_model_t
    real(wp) :: dynamic_viscosity = 1.0e-3_wp   !< Pa s, mu
    real(wp) :: outer_gap = 0.0_wp              !< m, h_out: the grid resolves the squeeze flow above it
    real(wp) :: roughness = 1.0e-9_wp           !< m, h_in: the force saturates below this gap
    logical :: tangential = .false.             !< the shear and rotation modes' log(1/xi) terms too
  end type lubrication_model_t

  !> Local geometry of the pair at its closest points.
  type :: lubrication_geometry_t
    real(wp) :: reduced_radius = 0.0_wp   !< m, R_eff = sqrt(2 / (tr K sqrt(det K)))
    real(wp) :: radius1 = 0.0_wp          !< m, a1 = 2 / tr K1 (mean radius of curvature at point1)
    real(wp) :: radius2 = 0.0_wp          !< m, a2 = 2 / tr K2
  end type lubrication_geometry_t

  !> What one lubrication update did (for outputs and tests).
  type :: lubrication_result_t
    logical :: active = .false.           !< h < h_out
    real(wp) :: resistance = 0.0_wp       !< N s/m, R_sub(h)
    real(wp) :: force(3) = 0.0_wp         !< N, on body 2 (body 1 receives -force), impulse / dt
    real(wp) :: point(3) = 0.0_wp         !< m, x_c
    real(wp) :: torque1(3) = 0.0_wp       !< N m, about the centre of body 1
    real(wp) :: torque2(3) = 0.0_wp       !< N m, about the centre of body 2
    real(wp) :: shear_resistance = 0.0_wp     !< N s/m, R_s (model%tangential)
    real(wp) :: rotation_resistance = 0.0_wp  !< N m s, R_r (model%tangential)
    type(lubrication_geometry_t) :: geometry
  end type lubrication_result_t

contains

  !> The model of &collision: h_out = lubrication_handover cells of the grid spacing, h_in =
  !> lubrication_roughness (config_checks has made sure h_in < h_out). Logs the settings.
  subroutine lubrication_setup(model, cfg, dynamic_viscosity, grid_spacing)
    type(lubrication_model_t), intent(out) :: model
    type(collision_config_t), intent(in) :: cfg
    real(wp), intent(in) :: dynamic_viscosity   !< Pa s
    real(wp), intent(in) :: grid_spacing        !< m, the smallest cell edge
    character(len=200) :: line
    model%dynamic_viscosity = dynamic_viscosity
    model%outer_gap = cfg%lubrication_handover * grid_spacing
    model%roughness = cfg%lubrication_roughness
    model%tangential = cfg%lubrication_tangential
    write(line, '(a,es11.4,a,f6.3,a,es11.4,a)') 'lubrication: sub-grid squeeze force below h_out = ', model%outer_gap, &
        ' m (', cfg%lubrication_handover, ' cells), saturated below h_in = ', model%roughness, ' m'
    call log_line(trim(line))
    if (model%tangential) call log_line('lubrication: with the tangential and rotational log(1/xi) terms')
  end subroutine lubrication_setup

  !> R_eff, a1, a2 from the principal curvatures of both surfaces at the closest points, projected on
  !> the common tangent plane (normal contact%normal).
  pure function lubrication_geometry(shape1, body1, shape2, body2, contact) result(geometry)
    type(spheroid_t), intent(in) :: shape1, shape2
    type(rigid_body_t), intent(in) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    type(lubrication_geometry_t) :: geometry
    real(wp) :: tangents(3, 2), k1(2, 2), k2(2, 2), k(2, 2), det
    tangents = tangent_basis(contact%normal)
    k1 = tangent_curvature(shape1, body1, contact%theta1, contact%phi1, tangents)
    k2 = tangent_curvature(shape2, body2, contact%theta2, contact%phi2, tangents)
    k = k1 + k2
    det = k(1, 1) * k(2, 2) - k(1, 2) * k(2, 1)
    geometry%reduced_radius = sqrt(2.0_wp / ((k(1, 1) + k(2, 2)) * sqrt(det)))
    geometry%radius1 = 2.0_wp / (k1(1, 1) + k1(2, 2))
    geometry%radius2 = 2.0_wp / (k2(1, 1) + k2(2, 2))
  end function lubrication_geometry

  !> Two unit vectors spanning the plane normal to n.
  pure function tangent_basis(normal) result(tangents)
    real(wp), intent(in) :: normal(3)
    real(wp) :: tangents(3, 2), n(3), reference_axis(3)
    n = normal / norm2(normal)
    reference_axis = [1.0_wp, 0.0_wp, 0.0_wp]
    if (abs(n(1)) > 0.6_wp) reference_axis = [0.0_wp, 1.0_wp, 0.0_wp]
    tangents(:, 1) = cross(n, reference_axis)
    tangents(:, 1) = tangents(:, 1) / norm2(tangents(:, 1))
    tangents(:, 2) = cross(n, tangents(:, 1))
  end function tangent_basis

  !> Curvature tensor of a spheroid surface at parametric angles (theta, phi), kappa_m t_m t_m^T +
  !> kappa_p t_p t_p^T in the lab frame, projected on the given tangent basis (2 x 2).
  pure function tangent_curvature(shape, body, theta, phi, tangents) result(k)
    type(spheroid_t), intent(in) :: shape
    type(rigid_body_t), intent(in) :: body
    real(wp), intent(in) :: theta, phi, tangents(3, 2)
    real(wp) :: k(2, 2), kappa_m, kappa_p, t_m(3), t_p(3), rotation(3, 3), pm(2), pp(2)
    integer :: i, j
    call principal_curvatures(shape, phi, kappa_m, kappa_p)
    call principal_directions(shape, theta, phi, t_m, t_p)
    rotation = rotation_matrix(body%quaternion)
    t_m = matmul(rotation, t_m)
    t_p = matmul(rotation, t_p)
    pm = matmul(t_m, tangents)
    pp = matmul(t_p, tangents)
    do j = 1, 2
      do i = 1, 2
        k(i, j) = kappa_m * pm(i) * pm(j) + kappa_p * pp(i) * pp(j)
      end do
    end do
  end function tangent_curvature

  !> R(h) (N s/m), the near-contact squeeze resistance of the module header, for h > 0.
  pure real(wp) function lubrication_resistance(model, geometry, gap)
    type(lubrication_model_t), intent(in) :: model
    type(lubrication_geometry_t), intent(in) :: geometry
    real(wp), intent(in) :: gap
    real(wp) :: l, xi, g2, g3, log_inverse
    l = geometry%radius2 / geometry%radius1
    xi = 2.0_wp * gap / (geometry%radius1 + geometry%radius2)
    g2 = l * (1.0_wp + 7.0_wp * l + l**2) / (5.0_wp * (1.0_wp + l)**3)
    g3 = (1.0_wp + 18.0_wp * l - 29.0_wp * l**2 + 18.0_wp * l**3 + l**4) / (42.0_wp * (1.0_wp + l)**3)
    log_inverse = log(1.0_wp / xi)
    lubrication_resistance = 6.0_wp * pi * model%dynamic_viscosity * (geometry%reduced_radius**2 / gap &
                             + geometry%radius1 * (g2 * log_inverse + g3 * xi * log_inverse))
  end function lubrication_resistance

  !> R_sub(h) = max(0, R(max(h, h_in)) - max(0, R(h_out))) below h_out, else 0 (module header).
  pure real(wp) function lubrication_subgrid_resistance(model, geometry, gap)
    type(lubrication_model_t), intent(in) :: model
    type(lubrication_geometry_t), intent(in) :: geometry
    real(wp), intent(in) :: gap
    lubrication_subgrid_resistance = 0.0_wp
    if (gap >= model%outer_gap) return
    ! The expansion turns negative at xi of about 1.7 (equal spheres): a particle-scale h_out (the
    ! 'stokes' and point rungs) or a sharp tip may lie beyond, where it subtracts nothing.
    lubrication_subgrid_resistance = max(0.0_wp, lubrication_resistance(model, geometry, max(gap, model%roughness)) &
                                     - max(0.0_wp, lubrication_resistance(model, geometry, model%outer_gap)))
  end function lubrication_subgrid_resistance

  !> [R_s, R_r]: the shear (N s/m) and relative-rotation (N m s) resistances of the tangential modes
  !> below h_out (module header), zero at and above it.
  pure function lubrication_tangential_resistances(model, geometry, gap) result(resistances)
    type(lubrication_model_t), intent(in) :: model
    type(lubrication_geometry_t), intent(in) :: geometry
    real(wp), intent(in) :: gap
    real(wp) :: resistances(2), l, a1, a2, log_sub, rotation_radius
    resistances = 0.0_wp
    if (gap >= model%outer_gap) return
    a1 = geometry%radius1
    a2 = geometry%radius2
    l = a2 / a1
    ! ln(1/xi) below the hand-over, saturated at the roughness gap; never negative (xi > 1 far out).
    log_sub = max(0.0_wp, log((a1 + a2) / (2.0_wp * max(gap, model%roughness)))) &
              - max(0.0_wp, log((a1 + a2) / (2.0_wp * model%outer_gap)))
    log_sub = max(0.0_wp, log_sub)
    rotation_radius = 2.0_wp * a1 * a2 / (a1 + a2)
    resistances(1) = 6.0_wp * pi * model%dynamic_viscosity * a1 &
                     * (4.0_wp / 15.0_wp) * l * (2.0_wp + l + 2.0_wp * l**2) / (1.0_wp + l)**3 * log_sub
    resistances(2) = 0.6_wp * pi * model%dynamic_viscosity * rotation_radius**3 * log_sub
  end function lubrication_tangential_resistances

  !> Apply the lubrication impulse of one step dt to both bodies (implicit in v_n; module header).
  pure subroutine lubricate(model, shape1, body1, shape2, body2, contact, dt, result, added1, added2)
    type(lubrication_model_t), intent(in) :: model
    type(spheroid_t), intent(in) :: shape1, shape2
    type(rigid_body_t), intent(inout) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    real(wp), intent(in) :: dt
    type(lubrication_result_t), intent(out) :: result
    type(added_inertia_t), intent(in), optional :: added1, added2   !< both or neither (module collision)
    real(wp) :: n(3), r1(3), r2(3), k(3, 3), inverse_mass(3, 3), normal_speed, j
    if (contact%gap >= model%outer_gap) return
    result%active = .true.
    result%geometry = lubrication_geometry(shape1, body1, shape2, body2, contact)
    result%resistance = lubrication_subgrid_resistance(model, result%geometry, contact%gap)
    n = contact%normal / norm2(contact%normal)
    result%point = 0.5_wp * (contact%point1 + contact%point2)
    r1 = result%point - body1%position
    r2 = result%point - body2%position
    normal_speed = dot_product(point_velocity(body1, result%point) - point_velocity(body2, result%point), n)
    ! An absent added1, added2 passes on as absent: the bodies alone.
    if (present(added1) .and. present(added2)) then
      inverse_mass = inverse_mass_lab(body1, added1) + inverse_mass_lab(body2, added2)
    else
      inverse_mass = isotropic_inverse_mass(1.0_wp / body1%mass + 1.0_wp / body2%mass)
    end if
    k = contact_matrix(inverse_mass, inverse_inertia_lab(body1, added1), r1, inverse_inertia_lab(body2, added2), r2)
    j = result%resistance * dt * normal_speed / (1.0_wp + result%resistance * dt * dot_product(n, matmul(k, n)))
    result%force = j / dt * n
    result%torque1 = cross(r1, -result%force)
    result%torque2 = cross(r2, result%force)
    call rigid_body_kick(body1, -result%force, result%torque1, dt, added1)
    call rigid_body_kick(body2, result%force, result%torque2, dt, added2)
    if (model%tangential) call lubricate_tangential(model, body1, body2, contact%gap, n, r1, r2, inverse_mass, dt, &
                                                    result, added1, added2)
  end subroutine lubricate

  !> The tangential modes' impulses after the normal one (module header): against the slip s_t at
  !> x_c and the relative rotation (omega1 - omega2)_t, each implicit along its own direction
  !> (j = R dt w / (1 + R dt e^T K e), w the speed, e its direction, K the pair's compliance for it).
  pure subroutine lubricate_tangential(model, body1, body2, gap, n, r1, r2, inverse_mass, dt, result, added1, added2)
    type(lubrication_model_t), intent(in) :: model
    type(rigid_body_t), intent(inout) :: body1, body2
    real(wp), intent(in) :: gap                       !< m, the surface gap h
    real(wp), intent(in) :: n(3), r1(3), r2(3)        !< the unit normal 1 -> 2; x_c - x_1, x_c - x_2
    real(wp), intent(in) :: inverse_mass(3, 3), dt    !< the pair's summed inverse (added) masses; s
    type(lubrication_result_t), intent(inout) :: result
    type(added_inertia_t), intent(in), optional :: added1, added2
    real(wp) :: resistances(2), slip(3), spin(3), speed, e(3), k(3, 3), inverse_inertia(3, 3), j, force(3), torque(3)
    resistances = lubrication_tangential_resistances(model, result%geometry, gap)
    result%shear_resistance = resistances(1)
    result%rotation_resistance = resistances(2)
    slip = point_velocity(body1, result%point) - point_velocity(body2, result%point)
    slip = slip - dot_product(slip, n) * n
    speed = norm2(slip)
    if (resistances(1) > 0.0_wp .and. speed > 0.0_wp) then
      e = slip / speed
      k = contact_matrix(inverse_mass, inverse_inertia_lab(body1, added1), r1, inverse_inertia_lab(body2, added2), r2)
      j = resistances(1) * dt * speed / (1.0_wp + resistances(1) * dt * dot_product(e, matmul(k, e)))
      force = j / dt * e
      call rigid_body_kick(body1, -force, cross(r1, -force), dt, added1)
      call rigid_body_kick(body2, force, cross(r2, force), dt, added2)
      result%force = result%force + force
      result%torque1 = result%torque1 + cross(r1, -force)
      result%torque2 = result%torque2 + cross(r2, force)
    end if
    spin = angular_velocity_lab(body1) - angular_velocity_lab(body2)
    spin = spin - dot_product(spin, n) * n
    speed = norm2(spin)
    if (resistances(2) > 0.0_wp .and. speed > 0.0_wp) then
      e = spin / speed
      inverse_inertia = inverse_inertia_lab(body1, added1) + inverse_inertia_lab(body2, added2)
      j = resistances(2) * dt * speed / (1.0_wp + resistances(2) * dt * dot_product(e, matmul(inverse_inertia, e)))
      torque = j / dt * e
      call rigid_body_kick(body1, [0.0_wp, 0.0_wp, 0.0_wp], -torque, dt, added1)
      call rigid_body_kick(body2, [0.0_wp, 0.0_wp, 0.0_wp], torque, dt, added2)
      result%torque1 = result%torque1 - torque
      result%torque2 = result%torque2 + torque
    end if
  end subroutine lubricate_tangential
end module lubrication
