! checks: 59
!> Unit tests of the sub-grid lubrication (src/particles/lubrication.f90; docs/theory.md, "Sub-grid
!> lubrication"): the resistance of two spheres against the near-contact expansion written out by
!> hand and against Brenner's exact series, the curvature-based reduced radius of a sphere facing a
!> needle (equator and tip), saturation below the roughness, nothing above the hand-over gap,
!> Newton's third law and momentum conservation, the torque of the off-centre application point,
!> the implicit update at a stiff gap, a particle-scale hand-over where the expansion is negative
!> (two needle tips), the particle system's step with lubrication switched on, every pair of a
!> periodic three-body system lubricated, and the tangential and rotational modes (model%tangential)
!> against Jeffrey & Onishi's (1984) near-contact coefficients of two equal spheres.
program test_lubrication
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use vector_algebra, only: cross
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, linear_momentum, angular_momentum, kinetic_energy, &
                        point_velocity, angular_velocity_lab, inverse_inertia_lab
  use quaternion, only: quaternion_normalise, rotate_to_lab
  use closest_points, only: closest_points_t, find_closest_points
  use lubrication, only: lubrication_model_t, lubrication_geometry_t, lubrication_result_t, lubrication_geometry, &
                         lubrication_resistance, lubrication_subgrid_resistance, lubrication_tangential_resistances, &
                         lubricate
  use particle_system, only: particle_models_t, particle_system_t, particle_system_create, particle_system_interact, &
                             particle_system_step, particle_interaction_gap
  use squeeze_case, only: brenner_squeeze_coefficient
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: mu = 1.0e-3_wp, density = 2710.0_wp, identity(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
  type(lubrication_model_t) :: model, wide
  type(spheroid_t) :: sphere1, sphere2, needle
  type(rigid_body_t) :: body1, body2
  type(closest_points_t) :: contact
  type(lubrication_geometry_t) :: geometry
  type(lubrication_result_t) :: result
  real(wp) :: a1, a2, gap, xi, expected, r_eff, kappa(2), quarter_turn(4), radius_tip, beta, eps
  real(wp) :: centre(3), orientation(4), p_before(3), l_before(3), e_before, v_before, v_after, force_expected(3)

  call test_start('lubrication')
  model = lubrication_model_t(dynamic_viscosity=mu, outer_gap=20.0e-6_wp, roughness=1.0e-9_wp)

  ! Two unequal spheres along x: R_eff = a1 a2 / (a1 + a2), a_i the radii (curvature 1/a_i).
  a1 = 50.0e-6_wp
  a2 = 30.0e-6_wp
  sphere1 = make_spheroid('sphere', a1, density)
  sphere2 = make_spheroid('sphere', a2, density)
  gap = 1.0e-6_wp
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, sphere2, [a1 + a2 + gap, 0.0_wp, 0.0_wp], identity)
  geometry = lubrication_geometry(sphere1, body1, sphere2, body2, contact)
  call check_close(geometry%reduced_radius, a1 * a2 / (a1 + a2), 1.0e-10_wp, 'spheres_reduced_radius')
  call check_close(geometry%radius1, a1, 1.0e-10_wp, 'spheres_radius1')
  call check_close(geometry%radius2, a2, 1.0e-10_wp, 'spheres_radius2')
  ! Leading term 6 pi mu R_eff^2 / h (Cox & Brenner 1967) plus Jeffrey & Onishi's (1984) X^A
  ! logarithmic terms, l = a2/a1 = 0.6: g2 = 0.6 (1 + 4.2 + 0.36) / (5 * 1.6^3), g3 = (1 + 10.8 -
  ! 10.44 + 3.888 + 0.1296) / (42 * 1.6^3), written out here independently of the module.
  xi = 2.0_wp * gap / (a1 + a2)
  expected = 6.0_wp * pi * mu * ((a1 * a2 / (a1 + a2))**2 / gap &
             + a1 * (0.6_wp * 5.56_wp / (5.0_wp * 4.096_wp) * log(1.0_wp / xi) &
                     + 5.3776_wp / (42.0_wp * 4.096_wp) * xi * log(1.0_wp / xi)))
  call check_close(lubrication_resistance(model, geometry, gap), expected, 1.0e-10_wp, 'unequal_spheres_resistance')

  ! Equal spheres against Brenner's exact series (squeeze_case): each sphere at U = v_n / 2, F = 6 pi
  ! mu a U beta, so R = 3 pi mu a beta up to the O(1) constant 1.3458 of the series (quoted by Costa
  ! et al. 2015) and O(eps): at eps = 1e-3 the remainder is below 2e-3 of 3 pi mu a.
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, sphere1, [2.0_wp * a1 + 1.0e-3_wp * a1, 0.0_wp, 0.0_wp], &
             identity)
  geometry = lubrication_geometry(sphere1, body1, sphere1, body2, contact)
  eps = 1.0e-3_wp
  beta = brenner_squeeze_coefficient(eps)
  call check_close(lubrication_resistance(model, geometry, eps * a1) / (3.0_wp * pi * mu * a1), beta - 1.3458_wp, &
                   0.0_wp, 'equal_spheres_vs_brenner_series', abs_tol=2.0e-3_wp)
  ! The series itself against its near-contact expansion 1/(2 eps) - (9/20) ln eps - (3/56) eps ln eps
  ! + 1.3458 at eps = 1e-2 (Costa et al. 2015 quote this expansion with 1.346).
  eps = 1.0e-2_wp
  call check_close(brenner_squeeze_coefficient(eps), 0.5_wp / eps - 0.45_wp * log(eps) - 3.0_wp / 56.0_wp * eps * log(eps) &
                   + 1.3458_wp, 0.0_wp, 'brenner_series_near_contact', abs_tol=5.0e-3_wp)

  ! Sphere facing a needle (a = 146.2 um, b = 29.24 um) whose axis is along z: the closest point is on
  ! its equator, principal curvatures b/a^2 along z and 1/b along y (docs/physics.md section 1).
  ! K = diag(1/a_s + 1/b, 1/a_s + b/a^2): R_eff^2 = 2 / (tr K sqrt(det K)).
  needle = make_spheroid('needle', 50.0e-6_wp, density)
  quarter_turn = quaternion_normalise([1.0_wp, 0.0_wp, -1.0_wp, 0.0_wp])   ! body x -> lab z
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, needle, [a1 + needle%b + gap, 0.0_wp, 0.0_wp], quarter_turn)
  geometry = lubrication_geometry(sphere1, body1, needle, body2, contact)
  kappa = [1.0_wp / a1 + 1.0_wp / needle%b, 1.0_wp / a1 + needle%b / needle%a**2]
  r_eff = sqrt(2.0_wp / (sum(kappa) * sqrt(product(kappa))))
  call check_close(geometry%reduced_radius, r_eff, 1.0e-9_wp, 'sphere_needle_equator_reduced_radius')
  call check_close(geometry%radius2, 2.0_wp / (1.0_wp / needle%b + needle%b / needle%a**2), 1.0e-9_wp, &
                   'needle_equator_mean_radius')
  ! Facing the needle's tip (umbilic, curvature a/b^2 both ways): two spheres of radii a1 and b^2/a.
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, needle, [0.0_wp, 0.0_wp, a1 + needle%a + gap], quarter_turn)
  geometry = lubrication_geometry(sphere1, body1, needle, body2, contact)
  radius_tip = needle%b**2 / needle%a
  call check_close(geometry%reduced_radius, a1 * radius_tip / (a1 + radius_tip), 1.0e-9_wp, &
                   'sphere_needle_tip_reduced_radius')

  ! Hand-over and saturation: R_sub = R(max(h, h_in)) - R(h_out) below h_out, 0 from h_out on.
  call check_close(lubrication_subgrid_resistance(model, geometry, 5.0e-6_wp), &
                   lubrication_resistance(model, geometry, 5.0e-6_wp) - lubrication_resistance(model, geometry, 20.0e-6_wp), &
                   1.0e-12_wp, 'subgrid_resistance_subtracts_resolved_part')
  call check_below(abs(lubrication_subgrid_resistance(model, geometry, 19.999e-6_wp)), &
                   1.0e-3_wp * lubrication_resistance(model, geometry, 20.0e-6_wp), 'subgrid_resistance_continuous_at_h_out')
  call check(lubrication_subgrid_resistance(model, geometry, 20.0e-6_wp) == 0.0_wp .and. &
             lubrication_subgrid_resistance(model, geometry, 1.0e-3_wp) == 0.0_wp, 'zero_from_h_out_on')
  call check_close(lubrication_subgrid_resistance(model, geometry, 1.0e-11_wp), &
                   lubrication_subgrid_resistance(model, geometry, 1.0e-9_wp), 1.0e-12_wp, 'saturated_below_roughness')
  call check(lubrication_subgrid_resistance(model, geometry, 1.0e-11_wp) > &
             2.0_wp * lubrication_subgrid_resistance(model, geometry, 1.0e-8_wp), 'grows_toward_roughness')

  ! A particle-scale hand-over (the 'stokes' and point rungs: one radius) between two needle tips
  ! (radius of curvature b^2/a = 5.85 um): the expansion is negative at h_out = 50 um (xi = 8.5) and
  ! from about xi = 1.7 (h = 10 um) on, so R_sub = max(0, R(h)): the full expansion near contact,
  ! nothing and no pull where it is negative (R(h) - R(h_out) would add a spurious positive offset).
  call place(needle, [0.0_wp, 0.0_wp, 0.0_wp], identity, needle, [2.0_wp * needle%a + gap, 0.0_wp, 0.0_wp], identity)
  geometry = lubrication_geometry(needle, body1, needle, body2, contact)
  call check_close(geometry%reduced_radius, 0.5_wp * needle%b**2 / needle%a, 1.0e-9_wp, 'needle_tips_reduced_radius')
  wide = lubrication_model_t(dynamic_viscosity=mu, outer_gap=50.0e-6_wp, roughness=1.0e-9_wp)
  call check(lubrication_resistance(wide, geometry, 50.0e-6_wp) < 0.0_wp .and. &
             lubrication_resistance(wide, geometry, 15.0e-6_wp) < 0.0_wp, 'needle_tips_expansion_negative_far_out')
  call check(lubrication_subgrid_resistance(wide, geometry, 15.0e-6_wp) == 0.0_wp, &
             'particle_scale_handover_nothing_where_expansion_negative')
  call check_close(lubrication_subgrid_resistance(wide, geometry, 1.0e-7_wp), lubrication_resistance(wide, geometry, 1.0e-7_wp), &
                   1.0e-12_wp, 'particle_scale_handover_full_expansion_near_contact')

  ! Above h_out: lubricate does nothing.
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, sphere2, [a1 + a2 + 25.0e-6_wp, 0.0_wp, 0.0_wp], identity)
  body1%velocity = [1.0e-3_wp, 0.0_wp, 0.0_wp]
  call lubricate(model, sphere1, body1, sphere2, body2, contact, 2.0e-7_wp, result)
  call check(.not. result%active .and. all(body1%velocity == [1.0e-3_wp, 0.0_wp, 0.0_wp]) .and. &
             all(body2%velocity == 0.0_wp), 'nothing_above_h_out')

  ! Off-centre approach of a sphere and a tilted needle, both moving and spinning: the force on the
  ! needle is R_sub v_n n (small R dt / m), momentum and angular momentum are conserved, the torques
  ! are the lever arms from the centres to x_c crossed with the forces, the energy does not grow.
  ! The sphere faces the needle's shoulder (off its mid-plane), where the normal misses the centre.
  orientation = quaternion_normalise([0.9_wp, 0.2_wp, -0.3_wp, 0.25_wp])
  centre = [a1 + 80.0e-6_wp, 90.0e-6_wp, 30.0e-6_wp] + 80.0e-6_wp * rotate_to_lab(orientation, [1.0_wp, 0.0_wp, 0.0_wp])
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, needle, centre, orientation)
  ! Slide the needle along the common normal to a 3 um gap.
  centre = body2%position - (contact%gap - 3.0e-6_wp) * contact%normal   ! copies: place redefines body2
  orientation = body2%quaternion
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, needle, centre, orientation)
  call rigid_body_of_spheroid(body1, sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, [2.0e-3_wp, 1.0e-3_wp, 0.0_wp], &
                              [10.0_wp, -5.0_wp, 3.0_wp])
  call rigid_body_of_spheroid(body2, needle, centre, orientation, [-1.0e-3_wp, 0.0_wp, 5.0e-4_wp], [-4.0_wp, 8.0_wp, 2.0_wp])
  call check(contact%gap > 0.0_wp .and. contact%gap < model%outer_gap, 'off_centre_pair_within_h_out')
  p_before = linear_momentum(body1) + linear_momentum(body2)
  l_before = angular_momentum(body1) + angular_momentum(body2)
  e_before = kinetic_energy(body1) + kinetic_energy(body2)
  v_before = normal_velocity()
  geometry = lubrication_geometry(sphere1, body1, needle, body2, contact)
  force_expected = lubrication_subgrid_resistance(model, geometry, contact%gap) * v_before * contact%normal
  call lubricate(model, sphere1, body1, needle, body2, contact, 1.0e-8_wp, result)
  call check(result%active, 'off_centre_active')
  call check_close(norm2(result%force - force_expected), 0.0_wp, 0.0_wp, 'force_is_resistance_times_normal_velocity', &
                   abs_tol=1.0e-4_wp * norm2(force_expected))   ! the implicit factor: R dt n.K n ~ 1e-5
  ! Round-off bounds, far below the impulse |F| dt (about 1e-5 of the momenta here).
  call check_below(norm2(linear_momentum(body1) + linear_momentum(body2) - p_before), &
                   1.0e-14_wp * (body1%mass + body2%mass) * 3.0e-3_wp, 'linear_momentum_conserved')
  call check_below(norm2(angular_momentum(body1) + angular_momentum(body2) - l_before), 1.0e-13_wp * norm2(l_before), &
                   'angular_momentum_conserved')
  call check(norm2(result%force) * 1.0e-8_wp > 1.0e6_wp * 1.0e-14_wp * (body1%mass + body2%mass) * 3.0e-3_wp, &
             'impulse_above_momentum_bound')
  call check_close(norm2(result%torque2 - cross(result%point - body2%position, result%force)), 0.0_wp, 0.0_wp, &
                   'torque_from_lever_arm_body2', abs_tol=1.0e-12_wp * norm2(result%force) * a1)
  call check_close(norm2(result%torque1 - cross(result%point - body1%position, -result%force)), 0.0_wp, 0.0_wp, &
                   'torque_from_lever_arm_body1', abs_tol=1.0e-12_wp * norm2(result%force) * a1)
  call check(norm2(result%torque2) > 1.0e-3_wp * norm2(result%force) * needle%b, 'off_centre_torque_nonzero')
  call check(kinetic_energy(body1) + kinetic_energy(body2) <= e_before, 'energy_not_increased')

  ! Stiff gap (R_sub dt / m >> 1): the implicit update brings v_n towards zero, never past it.
  call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, sphere1, [2.0_wp * a1 + 2.0e-9_wp, 0.0_wp, 0.0_wp], identity)
  body1%velocity = [1.0e-3_wp, 0.0_wp, 0.0_wp]
  v_before = normal_velocity()
  call lubricate(model, sphere1, body1, sphere1, body2, contact, 1.0e-5_wp, result)
  v_after = normal_velocity()
  call check(v_after >= 0.0_wp .and. v_after < 0.05_wp * v_before, 'stiff_gap_damped_not_reversed')

  call system_with_lubrication()
  call ring_with_lubrication()
  call tangential_modes()
  call test_finish()

contains

  !> Bodies at rest at the given centres and orientations, and their closest points.
  subroutine place(shape1, centre1, orientation1, shape2, centre2, orientation2)
    type(spheroid_t), intent(in) :: shape1, shape2
    real(wp), intent(in) :: centre1(3), orientation1(4), centre2(3), orientation2(4)
    call rigid_body_of_spheroid(body1, shape1, centre1, orientation1)
    call rigid_body_of_spheroid(body2, shape2, centre2, orientation2)
    call find_closest_points(shape1, centre1, orientation1, shape2, centre2, orientation2, contact)
    call check(contact%converged, 'closest_points_converged')
  end subroutine place

  !> (u1(x_c) - u2(x_c)).n of body1 and body2 at the contact's midpoint.
  real(wp) function normal_velocity()
    real(wp) :: xc(3)
    xc = 0.5_wp * (contact%point1 + contact%point2)
    normal_velocity = dot_product(point_velocity(body1, xc) - point_velocity(body2, xc), contact%normal)
  end function normal_velocity

  !> The tangential modes for two equal spheres (radius a, 10 nm apart along x, h_out = 20 um): the
  !> log(1/xi) coefficients of Jeffrey & Onishi (1984, J. Fluid Mech. 139, 261; as tabulated by Kim &
  !> Karrila 1991, ch. 11) at lambda = 1, with L = ln(h_out / h) the sub-grid part of ln(1/xi):
  !> Y^A_11 = 1/6 (force 6 pi mu a Y^A L v on a sphere translating past the other), Y^B_11 = 1/4
  !> (force 4 pi mu a^2 Y^B L omega on a spinning sphere), Y^C_11 = 1/5 and Y^C_12 = 1/20 (torques
  !> 8 pi mu a^3 Y^C L omega on the spinning sphere and on its neighbour); then a pair moving and
  !> spinning at random conserves momentum and angular momentum and loses kinetic energy.
  subroutine tangential_modes()
    type(lubrication_model_t) :: shear_model
    real(wp) :: a, h, log_sub, omega, resistances(2), p0(3), l0(3), e0
    a = a1
    h = 10.0e-9_wp
    omega = 20.0_wp
    shear_model = lubrication_model_t(dynamic_viscosity=mu, outer_gap=20.0e-6_wp, roughness=1.0e-9_wp, tangential=.true.)
    log_sub = log(20.0e-6_wp / h)
    call place(sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, sphere1, [2.0_wp * a + h, 0.0_wp, 0.0_wp], identity)
    geometry = lubrication_geometry(sphere1, body1, sphere1, body2, contact)
    resistances = lubrication_tangential_resistances(shear_model, geometry, h)
    call check_close(resistances(1), 6.0_wp * pi * mu * a * log_sub / 6.0_wp, 1.0e-9_wp, 'tangential_shear_resistance')
    call check_close(resistances(2), 0.6_wp * pi * mu * a**3 * log_sub, 1.0e-9_wp, 'tangential_rotation_resistance')
    call check(all(lubrication_tangential_resistances(shear_model, geometry, 20.0e-6_wp) == 0.0_wp), &
               'tangential_nothing_at_h_out')
    ! Translation past the other sphere (Y^A_11): force on body 2 along the motion, no torque but the lever's.
    call rigid_body_of_spheroid(body1, sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, [0.0_wp, 1.0e-3_wp, 0.0_wp])
    call lubricate(shear_model, sphere1, body1, sphere1, body2, contact, 1.0e-9_wp, result)
    call check_close(result%force(2), 6.0_wp * pi * mu * a * (1.0_wp / 6.0_wp) * log_sub * 1.0e-3_wp, 1.0e-3_wp, &
                     'jeffrey_onishi_YA11_force')
    ! Spin of body 1 about z (Y^B_11, Y^C_11).
    call rigid_body_of_spheroid(body1, sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, [0.0_wp, 0.0_wp, 0.0_wp], &
                                [0.0_wp, 0.0_wp, omega])
    call rigid_body_of_spheroid(body2, sphere1, [2.0_wp * a + h, 0.0_wp, 0.0_wp], identity)
    call lubricate(shear_model, sphere1, body1, sphere1, body2, contact, 1.0e-9_wp, result)
    call check_close(result%force(2), 4.0_wp * pi * mu * a**2 * 0.25_wp * log_sub * omega, 1.0e-3_wp, &
                     'jeffrey_onishi_YB11_force')
    call check_close(result%torque1(3), -8.0_wp * pi * mu * a**3 * 0.2_wp * log_sub * omega, 1.0e-3_wp, &
                     'jeffrey_onishi_YC11_torque')
    ! Spin of body 2 about z: the torque on body 1 (Y^C_12).
    call rigid_body_of_spheroid(body1, sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity)
    call rigid_body_of_spheroid(body2, sphere1, [2.0_wp * a + h, 0.0_wp, 0.0_wp], identity, [0.0_wp, 0.0_wp, 0.0_wp], &
                                [0.0_wp, 0.0_wp, omega])
    call lubricate(shear_model, sphere1, body1, sphere1, body2, contact, 1.0e-9_wp, result)
    call check_close(result%torque1(3), -8.0_wp * pi * mu * a**3 * 0.05_wp * log_sub * omega, 1.0e-3_wp, &
                     'jeffrey_onishi_YC12_torque')
    ! Random motion and spin: momentum and angular momentum conserved, kinetic energy not increased,
    ! and the step stays damping at a stiff time step (R_r dt / I >> 1).
    call rigid_body_of_spheroid(body1, sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, [1.0e-3_wp, -2.0e-3_wp, 5.0e-4_wp], &
                                [12.0_wp, -30.0_wp, 7.0_wp])
    call rigid_body_of_spheroid(body2, sphere1, [2.0_wp * a + h, 0.0_wp, 0.0_wp], identity, &
                                [-5.0e-4_wp, 1.0e-3_wp, 2.0e-3_wp], [-3.0_wp, 25.0_wp, -40.0_wp])
    p0 = linear_momentum(body1) + linear_momentum(body2)
    l0 = angular_momentum(body1) + angular_momentum(body2)
    e0 = kinetic_energy(body1) + kinetic_energy(body2)
    call lubricate(shear_model, sphere1, body1, sphere1, body2, contact, 1.0e-2_wp, result)
    call check_below(norm2(linear_momentum(body1) + linear_momentum(body2) - p0), 1.0e-13_wp * norm2(p0), &
                     'tangential_linear_momentum_conserved')
    call check_below(norm2(angular_momentum(body1) + angular_momentum(body2) - l0), 1.0e-12_wp * norm2(l0), &
                     'tangential_angular_momentum_conserved')
    call check(kinetic_energy(body1) + kinetic_energy(body2) < e0, 'tangential_energy_decreased')
    call check(result%shear_resistance * 1.0e-2_wp / body1%mass > 1.0_wp, 'tangential_stiff_step_case')
  end subroutine tangential_modes

  !> Two equal spheres approaching in the particle system: with lubrication the approach slows
  !> (a step's loss of v_n is the impulse over the reduced mass), without it nothing changes.
  subroutine system_with_lubrication()
    type(particle_system_t) :: system
    type(particle_models_t) :: models
    type(rigid_body_t) :: bodies(2)
    real(wp) :: dt, expected_force
    dt = 2.0e-7_wp
    call rigid_body_of_spheroid(bodies(1), sphere1, [0.0_wp, 0.0_wp, 0.0_wp], identity, [1.0e-3_wp, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(bodies(2), sphere1, [2.0_wp * a1 + 1.0e-6_wp, 0.0_wp, 0.0_wp], identity, &
                                [-1.0e-3_wp, 0.0_wp, 0.0_wp])
    call particle_system_create(system, [sphere1, sphere1], bodies, models)
    call particle_system_step(system, dt)
    call check(all(system%bodies(1)%velocity == [1.0e-3_wp, 0.0_wp, 0.0_wp]), 'system_without_lubrication_unchanged')
    models%lubrication = .true.
    models%lubrication_model = model
    call particle_system_create(system, [sphere1, sphere1], bodies, models)
    call particle_system_interact(system, dt)
    geometry = lubrication_geometry(sphere1, system%bodies(1), sphere1, system%bodies(2), system%pairs(1)%contact)
    expected_force = lubrication_subgrid_resistance(model, geometry, 1.0e-6_wp) * 2.0e-3_wp
    call check_close(system%lubrication_loads%force(1, 2), expected_force, 1.0e-2_wp, 'system_lubrication_force_on_body2')
    call check_close(system%lubrication_loads%force(1, 1), -system%lubrication_loads%force(1, 2), 1.0e-14_wp, &
                     'system_lubrication_third_law')
    call check_close(system%bodies(1)%velocity(1), 1.0e-3_wp - expected_force * dt / sphere1%mass, 1.0e-2_wp * &
                     expected_force * dt / sphere1%mass / 1.0e-3_wp, 'system_lubrication_slows_body1')
  end subroutine system_with_lubrication

  !> Every pair of a many-body system: three spheres in a line in a periodic box, 1 um apart, the
  !> third pair across the box's wrap, the broad phase's gap that of a many-body scene
  !> (particle_interaction_gap: the hand-over gap). Bodies 1 and 3 approach body 2 at 1 mm/s and
  !> separate from each other across the wrap (the film resists both): all three pairs are
  !> lubricated, at the same resistance, and the loads sum to zero.
  subroutine ring_with_lubrication()
    type(particle_system_t) :: system
    type(particle_models_t) :: models
    type(rigid_body_t) :: bodies(3)
    real(wp) :: pitch, box(3)
    integer :: n
    pitch = 2.0_wp * a1 + 1.0e-6_wp
    box = [3.0_wp * pitch, 4.0_wp * a1, 4.0_wp * a1]
    do n = 1, 3
      call rigid_body_of_spheroid(bodies(n), sphere1, [(n - 0.5_wp) * pitch, 2.0_wp * a1, 2.0_wp * a1], identity, &
                                  [(2 - n) * 1.0e-3_wp, 0.0_wp, 0.0_wp])
    end do
    models%lubrication = .true.
    models%lubrication_model = model
    models%interaction_gap = particle_interaction_gap(models)
    call particle_system_create(system, [sphere1, sphere1, sphere1], bodies, models, box_length=box)
    call particle_system_interact(system, 2.0e-7_wp)
    call check(size(system%pairs) == 3, 'ring_three_pair_records')
    call check(all(system%pairs%lubrication%active), 'ring_every_pair_lubricated')
    call check_close(minval(system%pairs%lubrication%resistance), maxval(system%pairs%lubrication%resistance), 1.0e-9_wp, &
                     'ring_pairs_same_resistance')
    call check_below(norm2(sum(system%lubrication_loads%force, dim=2)), 1.0e-12_wp * norm2(system%lubrication_loads%force), &
                     'ring_loads_sum_to_zero')
  end subroutine ring_with_lubrication
end program test_lubrication
