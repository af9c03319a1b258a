! checks: 54
!> Unit tests of dlvo: Eq. 13 force values for the paper's Table 1, Grahame/Debye constants,
!> curvature factor (Eq. 14 and Derjaguin) for spheres and needles, energy = integral of force,
!> torque balance, and finite values at the extremes.
program test_dlvo
  use agglo_kinds, only: wp
  use vector_algebra, only: cross
  use config_dlvo, only: dlvo_config_t
  use dlvo, only: dlvo_model_t, dlvo_setup, dlvo_force, dlvo_vdw_force, dlvo_edl_force, dlvo_energy, &
                  dlvo_pair_forces, chi_eta_eq14, chi_eta_derjaguin, alpha_sine_squared, curvature_factor, &
                  dlvo_log_constants, dlvo_evaluation_t, dlvo_evaluate, escape_energy, relative_normal_energy
  use spheroid, only: spheroid_t, make_spheroid
  use closest_points, only: closest_points_t, find_closest_points
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use quaternion, only: quaternion_from_axis_angle
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  type(dlvo_config_t) :: cfg
  type(dlvo_model_t) :: model, model_theta
  real(wp), parameter :: r = 50.0e-6_wp
  real(wp) :: lambda, k_m, k_p, chi, h, step, numeric, s2, angle
  real(wp) :: f1(3), t1(3), f2(3), t2(3), n(3), x1(3), x2(3), c1(3), c2(3), total_torque(3)
  real(wp) :: gaps(7), f, e
  logical :: finite
  integer :: i

  call test_start('dlvo')
  call dlvo_setup(model, cfg, r)          ! defaults = Table 1 (A 22.3 zJ, kappa 328947368 1/m,
  call dlvo_log_constants(model)          ! 3.7e-4 C/m^2, 293 K, eps_r 80.1, cut-off 5 nm)

  ! Reference numbers computed independently in Python (plain math module, the same CODATA/SI
  ! constants) from docs/physics.md section 7: n = kappa^2 eps_r eps0 kT / 2e^2, Grahame for psi0,
  ! Theta = tanh(e psi0 / 4kT), F = -A r/(12 max(h,5nm)^2) + 64 pi r n kT Theta^2 exp(-kappa h)/kappa.
  call check_close(model%ion_number_density, 6.046919645743229e24_wp, 1.0e-12_wp, 'ion_number_density_from_kappa')
  call check_close(model%surface_potential, 1.585706078703882e-3_wp, 1.0e-10_wp, 'grahame_surface_potential')
  call check_close(model%theta, 0.01569952474510733_wp, 1.0e-10_wp, 'theta_from_charge_density')
  call check_close(dlvo_force(model, 5.0e-9_wp, 1.0_wp), -3.681092772121891e-09_wp, 1.0e-10_wp, 'eq13_force_5nm')
  call check_close(dlvo_force(model, 10.0e-9_wp, 1.0_wp), -9.222986509628069e-10_wp, 1.0e-10_wp, 'eq13_force_10nm')
  call check_close(dlvo_force(model, 50.0e-9_wp, 1.0_wp), -3.7166653410125976e-11_wp, 1.0e-10_wp, 'eq13_force_50nm')
  call check_close(dlvo_vdw_force(model, 5.0e-9_wp, 1.0_wp), -3.716666666666666e-09_wp, 1.0e-12_wp, 'vdw_5nm')
  call check_close(dlvo_edl_force(model, 5.0e-9_wp, 1.0_wp), 3.5573894544775114e-11_wp, 1.0e-10_wp, 'edl_5nm')
  ! Cut-off (paper: 5 nm): the vdW term is constant below it.
  call check_close(dlvo_vdw_force(model, 1.0e-9_wp, 1.0_wp), dlvo_vdw_force(model, 5.0e-9_wp, 1.0_wp), 1.0e-14_wp, &
                   'vdw_constant_below_cutoff')
  ! chi_eta scales the whole force linearly (Eq. 13).
  call check_close(dlvo_force(model, 7.0e-9_wp, 2.5_wp), 2.5_wp * dlvo_force(model, 7.0e-9_wp, 1.0_wp), 1.0e-14_wp, &
                   'force_linear_in_chi_eta')

  ! Theta given directly reproduces the charge density (Grahame inverted) and the same force.
  cfg%surface_potential_from = 'theta'
  cfg%theta = model%theta
  call dlvo_setup(model_theta, cfg, r)
  call check_close(model_theta%surface_charge_density, 3.7e-4_wp, 1.0e-10_wp, 'theta_input_gives_charge_density')
  call check_close(dlvo_force(model_theta, 10.0e-9_wp, 1.0_wp), dlvo_force(model, 10.0e-9_wp, 1.0_wp), 1.0e-12_wp, &
                   'theta_input_same_force')
  cfg = dlvo_config_t()

  ! Energy (python, same formulas): U(5 nm) = -1.8475188693778787e-17 J, U(1 nm) = -3.304687001302807e-17 J.
  call check_close(dlvo_energy(model, 5.0e-9_wp, 1.0_wp), -1.8475188693778787e-17_wp, 1.0e-10_wp, 'energy_5nm')
  call check_close(dlvo_energy(model, 1.0e-9_wp, 1.0_wp), -3.304687001302807e-17_wp, 1.0e-10_wp, 'energy_1nm')
  ! F = -dU/dh by central differences, above and below the cut-off (chi_eta = 1.7).
  gaps = [0.5e-9_wp, 2.0e-9_wp, 4.0e-9_wp, 6.0e-9_wp, 10.0e-9_wp, 30.0e-9_wp, 100.0e-9_wp]
  do i = 1, size(gaps)
    h = gaps(i)
    step = 1.0e-4_wp * h
    numeric = -(dlvo_energy(model, h + step, 1.7_wp) - dlvo_energy(model, h - step, 1.7_wp)) / (2.0_wp * step)
    call check_close(numeric, dlvo_force(model, h, 1.7_wp), 1.0e-6_wp, 'force_is_minus_energy_gradient_'//gap_name(h))
  end do

  ! Equal spheres: all curvatures 1/r, chi_eta = 1 for any alpha, both forms (docs/physics.md sec. 7).
  do i = 0, 4
    s2 = real(i, wp) / 4.0_wp
    call check_close(chi_eta_eq14(r, 1/r, 1/r, 1/r, 1/r, s2), 1.0_wp, 1.0e-14_wp, 'spheres_chi_eta_eq14_'//char(48 + i))
    call check_close(chi_eta_derjaguin(r, 1/r, 1/r, 1/r, 1/r, s2), 1.0_wp, 1.0e-14_wp, &
                     'spheres_chi_eta_derjaguin_'//char(48 + i))
  end do

  ! Needles, aspect ratio lambda = 5, side by side at the equator (phi = pi/2). In units of r:
  ! a = lambda^(2/3), b = lambda^(-1/3); meridional k = b/a^2 = lambda^(-5/3), parallel k' = 1/b = lambda^(1/3).
  ! Parallel axes (alpha = 0): Eq. 14 = 2 / (k + k') = 2 lambda^(5/3) / (1 + lambda^2) = 2 * 14.620089 / 26 = 1.1246222;
  !   Derjaguin = 2 / sqrt(4 k k') = 1 / sqrt(lambda^(-4/3)) = lambda^(2/3) = 2.9240177.
  ! Crossed axes (alpha = 90 deg): Eq. 14 = 2 / sqrt((k - k')^2 + (k + k')^2) = sqrt(2) lambda^(5/3) / sqrt(1 + lambda^4)
  !   = 1.414214 * 14.620089 / 25.019992 = 0.8263763; Derjaguin = 2 / sqrt(2kk' + k^2 + k'^2) = 2/(k + k') = 1.1246222.
  lambda = 5.0_wp
  k_m = lambda**(-5.0_wp / 3.0_wp) / r
  k_p = lambda**(1.0_wp / 3.0_wp) / r
  call check_close(chi_eta_eq14(r, k_m, k_p, k_m, k_p, 0.0_wp), 1.1246222_wp, 1.0e-7_wp, 'parallel_needles_eq14')
  call check_close(chi_eta_derjaguin(r, k_m, k_p, k_m, k_p, 0.0_wp), 2.9240177_wp, 1.0e-7_wp, 'parallel_needles_derjaguin')
  call check_close(chi_eta_eq14(r, k_m, k_p, k_m, k_p, 1.0_wp), 0.8263763_wp, 1.0e-7_wp, 'crossed_needles_eq14')
  call check_close(chi_eta_derjaguin(r, k_m, k_p, k_m, k_p, 1.0_wp), 1.1246222_wp, 1.0e-7_wp, 'crossed_needles_derjaguin')
  ! The model's switch selects the form (default eq14).
  chi = curvature_factor(model, k_m, k_p, k_m, k_p, 1.0_wp)
  call check_close(chi, 0.8263763_wp, 1.0e-7_wp, 'model_default_is_eq14')

  ! alpha from the meridian tangents projected onto the tangent plane: t2 = t1 turned by 30 deg
  ! about n plus a normal component (removed by the projection): sin^2(30 deg) = 1/4.
  n = [0.0_wp, 0.0_wp, 1.0_wp]
  angle = acos(-1.0_wp) / 6.0_wp
  s2 = alpha_sine_squared([1.0_wp, 0.0_wp, 0.0_wp], [cos(angle), sin(angle), 3.0_wp], n)
  call check_close(s2, 0.25_wp, 1.0e-14_wp, 'alpha_projected_tangents')
  call check_close(alpha_sine_squared([0.0_wp, 0.0_wp, 1.0_wp], [1.0_wp, 0.0_wp, 0.0_wp], n), 0.0_wp, 0.0_wp, &
                   'alpha_degenerate_tangent_is_zero', abs_tol=0.0_wp)

  ! Forces at the closest points along n: equal and opposite, attractive at 10 nm, and the pair's
  ! torques about the origin cancel (x2 - x1 parallel to n) so angular momentum is conserved.
  n = [2.0_wp, -1.0_wp, 2.0_wp] / 3.0_wp
  c1 = [1.0e-5_wp, 3.0e-5_wp, -2.0e-5_wp]
  x1 = c1 + [4.0e-5_wp, 1.0e-5_wp, 2.0e-5_wp]
  x2 = x1 + 10.0e-9_wp * n
  c2 = x2 + [3.0e-5_wp, -3.0e-5_wp, 1.0e-5_wp]
  call dlvo_pair_forces(model, 10.0e-9_wp, 1.3_wp, n, x1, x2, c1, c2, f1, t1, f2, t2)
  call check_below(norm2(f1 + f2), 0.0_wp, 'pair_forces_opposite')
  call check_close(dot_product(f2, n), 1.3_wp * dlvo_force(model, 10.0e-9_wp, 1.0_wp), 1.0e-14_wp, 'force_on_2_along_n')
  call check(dot_product(f1, n) > 0.0_wp, 'attractive_pulls_1_towards_2')
  total_torque = t1 + cross(c1, f1) + t2 + cross(c2, f2)
  call check_below(norm2(total_torque), 1.0e-12_wp * (norm2(t1) + norm2(t2) + norm2(cross(c1, f1))), &
                   'pair_torque_about_origin_cancels')

  ! Extremes: overlap, zero gap, huge gap, tiny chi: finite values.
  finite = .true.
  do i = -3, 12
    h = sign(10.0_wp**(-real(abs(i), wp)), real(i, wp))
    f = dlvo_force(model, h, 1.0_wp)
    e = dlvo_energy(model, h, 1.0_wp)
    finite = finite .and. abs(f) < huge(1.0_wp) .and. f == f .and. abs(e) < huge(1.0_wp) .and. e == e
  end do
  f = dlvo_force(model, 0.0_wp, 1.0_wp)
  finite = finite .and. f == f .and. abs(f) < huge(1.0_wp)
  call check(finite, 'finite_at_extreme_gaps')

  call contact_checks()
  call test_finish()

contains

  !> The same factors from real contacts: closest points (module closest_points) of spheres and of
  !> needles side by side (parallel, and crossed by turning body 2 by 90 deg about the normal y).
  subroutine contact_checks()
    type(spheroid_t) :: sphere, needle
    type(rigid_body_t) :: body1, body2
    type(closest_points_t) :: contact
    type(dlvo_evaluation_t) :: ev
    real(wp) :: q2(4), lab_torque(3)
    sphere = make_spheroid('sphere', r, 2710.0_wp)
    needle = make_spheroid('needle', r, 2710.0_wp, 5.0_wp)
    call rigid_body_of_spheroid(body1, sphere, [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(body2, sphere, [1.0e-5_wp, 2.0_wp * r, 3.0e-5_wp] / norm2([1.0e-5_wp, 2.0_wp * r, 3.0e-5_wp]) &
                                * (2.0_wp * r + 8.0e-9_wp), [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call find_closest_points(sphere, body1%position, body1%quaternion, sphere, body2%position, body2%quaternion, contact)
    call dlvo_evaluate(model, sphere, body1, sphere, body2, contact, ev)
    call check_close(ev%chi_eta, 1.0_wp, 1.0e-12_wp, 'contact_spheres_chi_eta')
    call check_close(ev%force, dlvo_force(model, 8.0e-9_wp, 1.0_wp), 1.0e-6_wp, 'contact_spheres_force_8nm')
    ! Spheres: the force passes through both centres, so no torque.
    call check_below(norm2(ev%torque1) + norm2(ev%torque2), 1.0e-12_wp * norm2(ev%force1) * r, 'contact_spheres_no_torque')
    ! Parallel needles side by side at 10 nm.
    call rigid_body_of_spheroid(body1, needle, [0.0_wp, 0.0_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(body2, needle, [0.0_wp, 2.0_wp * needle%b + 10.0e-9_wp, 0.0_wp], [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
    call find_closest_points(needle, body1%position, body1%quaternion, needle, body2%position, body2%quaternion, contact)
    call dlvo_evaluate(model, needle, body1, needle, body2, contact, ev)
    call check_close(ev%chi_eta, 1.1246222_wp, 1.0e-7_wp, 'contact_parallel_needles_eq14')
    call check_close(contact%gap, 10.0e-9_wp, 1.0e-6_wp, 'contact_parallel_needles_gap')
    ! Crossed needles.
    q2 = quaternion_from_axis_angle([0.0_wp, 1.0_wp, 0.0_wp], acos(-1.0_wp) / 2.0_wp)
    call rigid_body_of_spheroid(body2, needle, [0.0_wp, 2.0_wp * needle%b + 10.0e-9_wp, 0.0_wp], q2)
    call find_closest_points(needle, body1%position, body1%quaternion, needle, body2%position, body2%quaternion, contact)
    call dlvo_evaluate(model, needle, body1, needle, body2, contact, ev)
    call check_close(ev%chi_eta, 0.8263763_wp, 1.0e-7_wp, 'contact_crossed_needles_eq14')
    ! Off-centre needle pair: torques, and the pair's angular momentum balance about the origin.
    q2 = quaternion_from_axis_angle([0.3_wp, 0.5_wp, 0.8_wp] / norm2([0.3_wp, 0.5_wp, 0.8_wp]), 0.9_wp)
    call rigid_body_of_spheroid(body2, needle, [6.0e-5_wp, 9.0e-5_wp, 2.0e-5_wp], q2)
    call find_closest_points(needle, body1%position, body1%quaternion, needle, body2%position, body2%quaternion, contact)
    call check(contact%converged .and. contact%gap > 0.0_wp, 'contact_oblique_needles_separated')
    call dlvo_evaluate(model, needle, body1, needle, body2, contact, ev)
    lab_torque = ev%torque1 + cross(body1%position, ev%force1) + ev%torque2 + cross(body2%position, ev%force2)
    call check_below(norm2(lab_torque), 1.0e-9_wp * norm2(ev%torque1), 'contact_oblique_torque_balance')
    call check(norm2(ev%torque1) > 0.0_wp, 'contact_oblique_has_torque')
    ! Bound-state energy: with Table 1 there is no EDL barrier, so the escape energy at the cut-off
    ! is -U(5 nm) = 1.8475e-17 J (equal spheres, docs/physics.md sec. 7: ~1.9e-17 J).
    call check_close(escape_energy(model, 5.0e-9_wp, 1.0_wp), 1.8475188693778787e-17_wp, 1.0e-9_wp, 'escape_energy_spheres_5nm')
    call check_close(relative_normal_energy(body1, body1, contact), 0.0_wp, 0.0_wp, 'relative_energy_at_rest', abs_tol=0.0_wp)
  end subroutine contact_checks

  function gap_name(gap) result(name)
    real(wp), intent(in) :: gap
    character(len=:), allocatable :: name
    character(len=16) :: buffer
    write(buffer, '(f6.1,a)') gap * 1.0e9_wp, 'nm'
    name = trim(adjustl(buffer))
  end function gap_name

end program test_dlvo
