!> DLVO interaction between two spheroids: Eq. 13 of the paper (Hamaker vdW attraction and
!> electric double-layer repulsion for equal spheres in the Derjaguin approximation,
!> Israelachvili 1992) scaled by a curvature factor chi_eta: Eq. 14 of the paper (Everaers &
!> Ejtehadi 2003, Schiller et al. 2011) by default, the exact Derjaguin factor as an option.
!> Sign convention: a scalar force F > 0 is repulsive. The force on particle 2 is +F n, on
!> particle 1 it is -F n (n = unit normal from particle 1 to particle 2), each applied at that
!> particle's closest point, so it also gives torque; as x2 - x1 is parallel to n the pair's
!> angular momentum is conserved. docs/physics.md section 7 has every formula used here.
module dlvo
  use agglo_kinds, only: wp
  use vector_algebra, only: cross
  use physical_constants, only: pi, boltzmann_constant, elementary_charge, vacuum_permittivity, avogadro_number
  use config_dlvo, only: dlvo_config_t
  use logger, only: log_line
  use spheroid, only: spheroid_t, principal_curvatures, principal_directions
  use quaternion, only: rotate_to_lab
  use closest_points, only: closest_points_t
  use rigid_body, only: rigid_body_t
  use collision, only: approach_speed
  implicit none
  private
  public :: dlvo_model_t, dlvo_setup, dlvo_log_constants, dlvo_force, dlvo_vdw_force, dlvo_edl_force, &
            dlvo_energy, dlvo_pair_forces, curvature_factor, chi_eta_eq14, chi_eta_derjaguin, &
            alpha_sine_squared, ion_number_density, grahame_surface_potential, reduced_surface_potential, &
            dlvo_evaluation_t, dlvo_evaluate, contact_curvature_factor, relative_normal_energy, escape_energy, &
            dlvo_range, dlvo_range_debye_lengths, dlvo_cutoff_gap, dlvo_cutoff_fraction
  public :: curvature_eq14, curvature_derjaguin, curvature_none

  integer, parameter :: curvature_eq14 = 1, curvature_derjaguin = 2, curvature_none = 3

  !> The range of the DLVO well in Debye lengths (docs/theory.md, "Run outcome"): the EDL term has
  !> fallen by exp(-60) ~ 1e-26 there, so the barrier and any secondary minimum lie well inside,
  !> and beyond it only the weak vdW tail is left (U < 0, rising to 0).
  real(wp), parameter :: dlvo_range_debye_lengths = 60.0_wp

  !> The DLVO cut-off of a many-body system (docs/theory.md, "Particle system"): a pair is left
  !> out where each term of Eq. 13 has fallen below this fraction of its contact value (vdW at the
  !> cut-off gap c, EDL at h = 0). The vdW tail ~ 1/h^2 sets the range, h = c / sqrt(f) = 100 c;
  !> there the neglected energy, ~ 1/h, is 1% of the vdW energy at c (U(h) / U(c) = c / h).
  real(wp), parameter :: dlvo_cutoff_fraction = 1.0e-4_wp

  !> Every constant of Eq. 13, derived once from the deck (&dlvo) and the particle radius.
  type :: dlvo_model_t
    real(wp) :: hamaker = 0.0_wp                 !< J
    real(wp) :: debye_kappa = 0.0_wp             !< 1/m
    real(wp) :: temperature = 0.0_wp             !< K
    real(wp) :: relative_permittivity = 0.0_wp   !< -
    integer :: valence = 1                       !< z
    real(wp) :: ion_number_density = 0.0_wp      !< n, 1/m^3, from kappa
    real(wp) :: surface_charge_density = 0.0_wp  !< C/m^2 (from Grahame when Theta is given)
    real(wp) :: surface_potential = 0.0_wp       !< psi0, V
    real(wp) :: theta = 0.0_wp                   !< reduced surface potential Theta
    real(wp) :: radius = 0.0_wp                  !< r = sigma: volume-equivalent radius, m
    real(wp) :: vdw_cutoff = 0.0_wp              !< m
    integer :: curvature_form = curvature_eq14
    real(wp) :: vdw_coefficient = 0.0_wp         !< A r / 12, N m^2
    real(wp) :: edl_coefficient = 0.0_wp         !< 64 pi r n k_B T Theta^2 / kappa, N
  end type dlvo_model_t

  !> Everything Eq. 13 gives for one pair configuration (outputs: force_dlvo, torque_dlvo, chi_eta,
  !> vdw_force of particles.h5).
  type :: dlvo_evaluation_t
    real(wp) :: chi_eta = 1.0_wp       !< curvature factor used
    real(wp) :: force = 0.0_wp         !< N, scalar total (> 0 repulsive)
    real(wp) :: vdw_force = 0.0_wp     !< N, scalar vdW part (< 0)
    real(wp) :: edl_force = 0.0_wp     !< N, scalar EDL part (> 0)
    real(wp) :: energy = 0.0_wp        !< J, U(h) at the same chi_eta
    real(wp) :: force1(3) = 0.0_wp, torque1(3) = 0.0_wp   !< lab, on body 1 (torque about its centre)
    real(wp) :: force2(3) = 0.0_wp, torque2(3) = 0.0_wp   !< lab, on body 2
  end type dlvo_evaluation_t

contains

  !> chi_eta at the closest points: curvatures from each point's parametric phi (k = meridional,
  !> k' = parallel, docs/physics.md sec. 7), alpha between the two meridian tangents (turned to the lab
  !> frame) projected onto the tangent plane of the common normal.
  pure real(wp) function contact_curvature_factor(model, shape1, orientation1, shape2, orientation2, contact)
    type(dlvo_model_t), intent(in) :: model
    type(spheroid_t), intent(in) :: shape1, shape2
    real(wp), intent(in) :: orientation1(4), orientation2(4)
    type(closest_points_t), intent(in) :: contact
    real(wp) :: k1, k1p, k2, k2p, meridian1(3), meridian2(3), parallel(3)
    call principal_curvatures(shape1, contact%phi1, k1, k1p)
    call principal_curvatures(shape2, contact%phi2, k2, k2p)
    call principal_directions(shape1, contact%theta1, contact%phi1, meridian1, parallel)
    call principal_directions(shape2, contact%theta2, contact%phi2, meridian2, parallel)
    contact_curvature_factor = curvature_factor(model, k1, k1p, k2, k2p, &
        alpha_sine_squared(rotate_to_lab(orientation1, meridian1), rotate_to_lab(orientation2, meridian2), contact%normal))
  end function contact_curvature_factor

  !> Eq. 13 for the pair: chi_eta at the closest points, forces along the normal at the closest points.
  pure subroutine dlvo_evaluate(model, shape1, body1, shape2, body2, contact, evaluation)
    type(dlvo_model_t), intent(in) :: model
    type(spheroid_t), intent(in) :: shape1, shape2
    type(rigid_body_t), intent(in) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    type(dlvo_evaluation_t), intent(out) :: evaluation
    evaluation%chi_eta = contact_curvature_factor(model, shape1, body1%quaternion, shape2, body2%quaternion, contact)
    evaluation%vdw_force = dlvo_vdw_force(model, contact%gap, evaluation%chi_eta)
    evaluation%edl_force = dlvo_edl_force(model, contact%gap, evaluation%chi_eta)
    evaluation%force = evaluation%vdw_force + evaluation%edl_force
    evaluation%energy = dlvo_energy(model, contact%gap, evaluation%chi_eta)
    call dlvo_pair_forces(model, contact%gap, evaluation%chi_eta, contact%normal, contact%point1, contact%point2, &
                          body1%position, body2%position, evaluation%force1, evaluation%torque1, evaluation%force2, &
                          evaluation%torque2)
  end subroutine dlvo_evaluate

  !> Kinetic energy available to separate the pair (bound-state test, docs/physics.md sec. 7): the normal
  !> relative velocity of the closest points with the reduced mass, mu v_n^2 / 2 (the pair's common
  !> rotation is not energy that can separate it).
  pure real(wp) function relative_normal_energy(body1, body2, contact)
    type(rigid_body_t), intent(in) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    real(wp) :: normal_speed, reduced_mass
    normal_speed = approach_speed(body1, body2, contact%point1, contact%point2, contact%normal)
    reduced_mass = body1%mass * body2%mass / (body1%mass + body2%mass)
    relative_normal_energy = 0.5_wp * reduced_mass * normal_speed**2
  end function relative_normal_energy

  !> Energy needed to escape from gap h to infinity at fixed chi_eta: max(0, max_{h' >= h} U(h')) - U(h)
  !> (the EDL barrier, if any, lies within a few Debye lengths; beyond dlvo_range U < 0 and rises to 0,
  !> so the maximum is searched over [h, h + dlvo_range]).
  !> The pair is bound when relative_normal_energy < escape_energy.
  pure real(wp) function escape_energy(model, gap, chi_eta)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, chi_eta
    real(wp) :: top, h, span
    integer :: i
    integer, parameter :: samples = 400
    top = 0.0_wp
    span = dlvo_range(model)
    do i = 0, samples
      h = max(gap, 0.0_wp) + span * (real(i, wp) / samples)**2
      top = max(top, dlvo_energy(model, h, chi_eta))
    end do
    escape_energy = top - dlvo_energy(model, gap, chi_eta)
  end function escape_energy

  !> Range of the DLVO well (m): dlvo_range_debye_lengths Debye lengths, and at least the vdW cut-off.
  pure real(wp) function dlvo_range(model)
    type(dlvo_model_t), intent(in) :: model
    dlvo_range = max(dlvo_range_debye_lengths / model%debye_kappa, model%vdw_cutoff)
  end function dlvo_range

  !> Surface gap (m) beyond which both terms of Eq. 13 are below fraction (default
  !> dlvo_cutoff_fraction) of their contact values: vdW (c / h)^2 <= f beyond h = c / sqrt(f), EDL
  !> exp(-kappa h) <= f beyond h = ln(1/f) / kappa. chi_eta scales both terms alike, so the gap
  !> holds for every pair of shapes and orientations.
  pure real(wp) function dlvo_cutoff_gap(model, fraction)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in), optional :: fraction
    real(wp) :: f
    f = dlvo_cutoff_fraction
    if (present(fraction)) f = fraction
    dlvo_cutoff_gap = 0.0_wp
    if (model%vdw_coefficient /= 0.0_wp) dlvo_cutoff_gap = model%vdw_cutoff / sqrt(f)
    if (model%edl_coefficient /= 0.0_wp .and. model%debye_kappa > 0.0_wp) &
      dlvo_cutoff_gap = max(dlvo_cutoff_gap, log(1.0_wp / f) / model%debye_kappa)
  end function dlvo_cutoff_gap

  !> Ion number density of a z:z electrolyte from the Debye parameter:
  !> kappa^2 = 2 n z^2 e^2 / (eps_r eps0 k_B T) (Israelachvili 1992, ch. 12).
  pure real(wp) function ion_number_density(kappa, relative_permittivity, temperature, valence)
    real(wp), intent(in) :: kappa, relative_permittivity, temperature
    integer, intent(in) :: valence
    ion_number_density = kappa**2 * relative_permittivity * vacuum_permittivity * boltzmann_constant * temperature &
                         / (2.0_wp * real(valence, wp)**2 * elementary_charge**2)
  end function ion_number_density

  !> Grahame's equation solved for psi0: sigma_s = sqrt(8 eps_r eps0 n k_B T) sinh(z e psi0 / 2 k_B T).
  pure real(wp) function grahame_surface_potential(charge_density, n, relative_permittivity, temperature, valence)
    real(wp), intent(in) :: charge_density, n, relative_permittivity, temperature
    integer, intent(in) :: valence
    real(wp) :: kt
    kt = boltzmann_constant * temperature
    grahame_surface_potential = 2.0_wp * kt / (real(valence, wp) * elementary_charge) &
        * asinh(charge_density / sqrt(8.0_wp * relative_permittivity * vacuum_permittivity * n * kt))
  end function grahame_surface_potential

  !> Theta = tanh(z e psi0 / 4 k_B T).
  pure real(wp) function reduced_surface_potential(psi0, temperature, valence)
    real(wp), intent(in) :: psi0, temperature
    integer, intent(in) :: valence
    reduced_surface_potential = tanh(real(valence, wp) * elementary_charge * psi0 / (4.0_wp * boltzmann_constant * temperature))
  end function reduced_surface_potential

  !> Build the model from the deck group and the volume-equivalent radius r (= sigma of Eq. 14).
  subroutine dlvo_setup(model, cfg, radius)
    type(dlvo_model_t), intent(out) :: model
    type(dlvo_config_t), intent(in) :: cfg
    real(wp), intent(in) :: radius
    real(wp) :: kt, x
    model%hamaker = cfg%hamaker
    model%debye_kappa = cfg%debye_kappa
    model%temperature = cfg%temperature
    model%relative_permittivity = cfg%relative_permittivity
    model%valence = cfg%valence
    model%radius = radius
    model%vdw_cutoff = cfg%vdw_cutoff
    select case (cfg%curvature_factor)
    case ('derjaguin'); model%curvature_form = curvature_derjaguin
    case ('none'); model%curvature_form = curvature_none
    case default; model%curvature_form = curvature_eq14
    end select
    kt = boltzmann_constant * cfg%temperature
    model%ion_number_density = ion_number_density(cfg%debye_kappa, cfg%relative_permittivity, cfg%temperature, cfg%valence)
    if (cfg%surface_potential_from == 'theta') then
      model%theta = cfg%theta
      ! psi0 = (4 k_B T / z e) artanh(Theta); the charge density then follows from Grahame.
      x = min(abs(cfg%theta), 1.0_wp - epsilon(1.0_wp))
      model%surface_potential = sign(4.0_wp * kt / (cfg%valence * elementary_charge) * atanh(x), cfg%theta)
      model%surface_charge_density = sqrt(8.0_wp * cfg%relative_permittivity * vacuum_permittivity &
          * model%ion_number_density * kt) * sinh(cfg%valence * elementary_charge * model%surface_potential / (2.0_wp * kt))
    else
      model%surface_charge_density = cfg%surface_charge_density
      model%surface_potential = grahame_surface_potential(cfg%surface_charge_density, model%ion_number_density, &
          cfg%relative_permittivity, cfg%temperature, cfg%valence)
      model%theta = reduced_surface_potential(model%surface_potential, cfg%temperature, cfg%valence)
    end if
    model%vdw_coefficient = cfg%hamaker * radius / 12.0_wp
    model%edl_coefficient = 64.0_wp * pi * radius * model%ion_number_density * kt * model%theta**2 / cfg%debye_kappa
  end subroutine dlvo_setup

  !> Van der Waals part of Eq. 13 (scalar, > 0 repulsive, so negative): -chi A r / (12 max(h, cutoff)^2).
  pure real(wp) function dlvo_vdw_force(model, gap, chi_eta)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, chi_eta
    dlvo_vdw_force = -chi_eta * model%vdw_coefficient / max(gap, model%vdw_cutoff)**2
  end function dlvo_vdw_force

  !> Double-layer part of Eq. 13: chi 64 pi r n k_B T Theta^2 exp(-kappa h) / kappa (no cut-off:
  !> it is finite at h = 0; for an overlap h < 0 the gap is taken as 0 so nothing blows up).
  pure real(wp) function dlvo_edl_force(model, gap, chi_eta)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, chi_eta
    dlvo_edl_force = chi_eta * model%edl_coefficient * exp(-model%debye_kappa * max(gap, 0.0_wp))
  end function dlvo_edl_force

  !> Eq. 13: total DLVO force (scalar, > 0 repulsive) at surface gap h with curvature factor chi_eta.
  pure real(wp) function dlvo_force(model, gap, chi_eta)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, chi_eta
    dlvo_force = dlvo_vdw_force(model, gap, chi_eta) + dlvo_edl_force(model, gap, chi_eta)
  end function dlvo_force

  !> Interaction energy U(h) = integral from h to infinity of F(h') dh' at fixed chi_eta (the same
  !> scaling as the force), zero at infinite separation:
  !>   vdW: -chi A r / (12 h) for h >= c;  -chi A r / (12 c) - chi A r (c - h) / (12 c^2) for h < c
  !>   EDL: +chi 64 pi r n k_B T Theta^2 exp(-kappa h) / kappa^2.
  pure real(wp) function dlvo_energy(model, gap, chi_eta)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, chi_eta
    real(wp) :: c, vdw
    c = model%vdw_cutoff
    if (gap >= c) then
      vdw = -model%vdw_coefficient / gap
    else
      vdw = -model%vdw_coefficient / c - model%vdw_coefficient * (c - gap) / c**2
    end if
    dlvo_energy = chi_eta * (vdw + model%edl_coefficient * exp(-model%debye_kappa * max(gap, 0.0_wp)) / model%debye_kappa)
  end function dlvo_energy

  !> sin^2(alpha), alpha = angle between the meridian tangents t1, t2 of the two bodies projected
  !> onto the common tangent plane (normal n). A tangent parallel to n (degenerate) gives 0.
  pure real(wp) function alpha_sine_squared(tangent1, tangent2, normal)
    real(wp), intent(in) :: tangent1(3), tangent2(3), normal(3)
    real(wp) :: p1(3), p2(3), c(3), n1, n2
    p1 = tangent1 - dot_product(tangent1, normal) * normal
    p2 = tangent2 - dot_product(tangent2, normal) * normal
    n1 = dot_product(p1, p1)
    n2 = dot_product(p2, p2)
    if (n1 <= tiny(1.0_wp) .or. n2 <= tiny(1.0_wp)) then
      alpha_sine_squared = 0.0_wp
      return
    end if
    c = [p1(2) * p2(3) - p1(3) * p2(2), p1(3) * p2(1) - p1(1) * p2(3), p1(1) * p2(2) - p1(2) * p2(1)]
    alpha_sine_squared = min(1.0_wp, dot_product(c, c) / (n1 * n2))
  end function alpha_sine_squared

  !> Eq. 14 of the paper with curvatures k = 1/R (meridional) and k' = 1/R' (parallel) of each body
  !> (labelling of docs/physics.md section 7) and sigma = r:
  !> chi_eta = (2/r) / sqrt((k1 - k1')(k2 - k2') sin^2 alpha + (k1 + k1')(k2 + k2')).
  pure real(wp) function chi_eta_eq14(radius, k1, k1p, k2, k2p, sin2_alpha)
    real(wp), intent(in) :: radius, k1, k1p, k2, k2p, sin2_alpha
    chi_eta_eq14 = (2.0_wp / radius) / sqrt((k1 - k1p) * (k2 - k2p) * sin2_alpha + (k1 + k1p) * (k2 + k2p))
  end function chi_eta_eq14

  !> Exact Derjaguin factor of two curved surfaces: (2/r) / sqrt(det(K1 + K2)) with
  !> det = k1 k1' + k2 k2' + (k1 k2 + k1' k2') sin^2 alpha + (k1 k2' + k1' k2) cos^2 alpha.
  pure real(wp) function chi_eta_derjaguin(radius, k1, k1p, k2, k2p, sin2_alpha)
    real(wp), intent(in) :: radius, k1, k1p, k2, k2p, sin2_alpha
    real(wp) :: det
    det = k1 * k1p + k2 * k2p + (k1 * k2 + k1p * k2p) * sin2_alpha + (k1 * k2p + k1p * k2) * (1.0_wp - sin2_alpha)
    chi_eta_derjaguin = (2.0_wp / radius) / sqrt(det)
  end function chi_eta_derjaguin

  !> The model's curvature factor (deck: &dlvo curvature_factor).
  pure real(wp) function curvature_factor(model, k1, k1p, k2, k2p, sin2_alpha)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: k1, k1p, k2, k2p, sin2_alpha
    select case (model%curvature_form)
    case (curvature_derjaguin)
      curvature_factor = chi_eta_derjaguin(model%radius, k1, k1p, k2, k2p, sin2_alpha)
    case (curvature_none)
      curvature_factor = 1.0_wp
    case default
      curvature_factor = chi_eta_eq14(model%radius, k1, k1p, k2, k2p, sin2_alpha)
    end select
  end function curvature_factor

  !> Lab-frame force and torque (about each centre) on both particles from Eq. 13.
  !> point1/point2: closest points on bodies 1/2; normal: unit vector from 1 to 2; centre1/centre2:
  !> the bodies' centres. Forces act at the closest points, along the normal.
  pure subroutine dlvo_pair_forces(model, gap, chi_eta, normal, point1, point2, centre1, centre2, &
                                   force1, torque1, force2, torque2)
    type(dlvo_model_t), intent(in) :: model
    real(wp), intent(in) :: gap, chi_eta, normal(3), point1(3), point2(3), centre1(3), centre2(3)
    real(wp), intent(out) :: force1(3), torque1(3), force2(3), torque2(3)
    real(wp) :: magnitude
    magnitude = dlvo_force(model, gap, chi_eta)
    force2 = magnitude * normal
    force1 = -force2
    torque1 = cross(point1 - centre1, force1)
    torque2 = cross(point2 - centre2, force2)
  end subroutine dlvo_pair_forces

  !> Log every derived constant and the equal-sphere force at 5, 10 and 50 nm (chi_eta = 1).
  subroutine dlvo_log_constants(model)
    type(dlvo_model_t), intent(in) :: model
    character(len=200) :: line
    character(len=16), parameter :: form_names(3) = [character(len=16) :: 'eq14', 'derjaguin', 'none']
    real(wp), parameter :: gaps(3) = [5.0e-9_wp, 10.0e-9_wp, 50.0e-9_wp]
    integer :: i
    call log_line('dlvo: Eq. 13 with curvature factor '''//trim(form_names(model%curvature_form))//'''')
    write(line, '(a,es12.5,a,es12.5,a,f8.3,a,f7.2,a,i0)') 'dlvo: Hamaker A = ', model%hamaker, ' J, kappa = ', &
        model%debye_kappa, ' 1/m (Debye length ', 1.0e9_wp / model%debye_kappa, ' nm), T = ', model%temperature, &
        ' K, z = ', model%valence
    call log_line(trim(line))
    write(line, '(a,f8.3,a,es12.5,a,f9.4,a)') 'dlvo: eps_r = ', model%relative_permittivity, &
        ', ion number density n = ', model%ion_number_density, ' 1/m^3 (', &
        model%ion_number_density / avogadro_number, ' mM)'   ! n / N_A in mol/m^3 = mM
    call log_line(trim(line))
    write(line, '(a,es12.5,a,es12.5,a,es12.5)') 'dlvo: surface charge density = ', model%surface_charge_density, &
        ' C/m^2, psi0 = ', model%surface_potential, ' V, Theta = ', model%theta
    call log_line(trim(line))
    write(line, '(a,es12.5,a,es12.5,a,es12.5,a)') 'dlvo: r = ', model%radius, ' m, vdW cut-off = ', model%vdw_cutoff, &
        ' m, well depth at the cut-off (equal spheres) = ', dlvo_energy(model, model%vdw_cutoff, 1.0_wp), ' J'
    call log_line(trim(line))
    do i = 1, size(gaps)
      write(line, '(a,f5.1,a,es13.5,a,es13.5,a,es13.5,a)') 'dlvo: equal spheres at h = ', gaps(i) * 1.0e9_wp, &
          ' nm: F = ', dlvo_force(model, gaps(i), 1.0_wp), ' N (vdW ', dlvo_vdw_force(model, gaps(i), 1.0_wp), &
          ', EDL ', dlvo_edl_force(model, gaps(i), 1.0_wp), '; > 0 repulsive)'
      call log_line(trim(line))
    end do
  end subroutine dlvo_log_constants
end module dlvo
