! checks: 21
!> Unit tests of pair_outcome (docs/theory.md, "Run outcome"): two calcite spheres (r = 50 um, the
!> paper's Table 1 DLVO constants: Debye length 3.04 nm, so the DLVO range is 60 of them, 182 nm)
!> in the states that separate the outcomes and decide whether they are settled.
program test_pair_outcome
  use agglo_kinds, only: wp
  use config_dlvo, only: dlvo_config_t
  use config_collision, only: collision_config_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use closest_points, only: closest_points_t, find_closest_points
  use dlvo, only: dlvo_setup, escape_energy, relative_normal_energy
  use collision, only: collision_setup
  use particle_system, only: particle_models_t
  use pair_outcome, only: pair_outcome_t, pair_outcome_rules_t, pair_outcome_rules_of, pair_outcome_of
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp
  type(particle_models_t) :: models
  type(pair_outcome_rules_t) :: rules
  type(spheroid_t) :: sphere

  call test_start('pair_outcome')
  sphere = make_spheroid('sphere', radius, density)
  models%dlvo = .true.
  call dlvo_setup(models%dlvo_model, dlvo_config_t(), radius)
  models%collisions = .true.
  call collision_setup(models%collision_model, collision_config_t())
  rules = pair_outcome_rules_of(models)
  ! 60 Debye lengths, 1/kappa = 1 / 328947368 m (Table 1).
  call check_close(rules%dlvo_range, 60.0_wp / 328947368.0_wp, 1.0e-12_wp, 'dlvo_range_is_60_debye_lengths')
  call check_close(rules%contact_gap, 5.0e-9_wp, 1.0e-12_wp, 'contact_gap_is_the_vdw_cutoff')

  ! The issue's Stokes pair: collided once, stopped by the drag 0.92 um apart. It has no kinetic
  ! energy, so the energy test alone calls it bound (the old rule: 'agglomerated'); it is outside
  ! the well's range: rebounded. At rest it is settled; drifting back (2.3e-7 m/s) it is in flight.
  call expect('stopped_far_apart', .true., 0.92e-6_wp, 0.0_wp, 'rebounded', .true., bound=.true.)
  call expect('drifting_back_far_apart', .true., 0.92e-6_wp, 2.3e-7_wp, 'rebounded', .false.)
  ! In contact and at rest: agglomerated, settled.
  call expect('resting_in_contact', .true., 1.0e-9_wp, 0.0_wp, 'agglomerated', .true.)
  ! 50 nm apart inside the well, separating at 1e-5 m/s (mu v^2 / 2 below the escape energy):
  ! agglomerated, but in flight (it will come back to contact).
  call expect('inside_well_bound_in_flight', .true., 50.0e-9_wp, -1.0e-5_wp, 'agglomerated', .false., bound=.true.)
  ! The same at 1 mm/s: not bound, rebounded, still in flight inside the range.
  call expect('inside_well_escaping', .true., 50.0e-9_wp, -1.0e-3_wp, 'rebounded', .false., bound=.false.)
  ! Beyond the range and separating: rebounded, settled.
  call expect('escaped', .true., 1.0e-6_wp, -1.0e-3_wp, 'rebounded', .true.)
  ! Never collided: no_contact, settled only when beyond the range and not approaching.
  call expect('never_touched_at_rest', .false., 3.0e-6_wp, 0.0_wp, 'no_contact', .true.)
  call expect('never_touched_approaching', .false., 3.0e-6_wp, 1.0e-4_wp, 'no_contact', .false.)
  call test_finish()

contains

  !> Two spheres on the x axis at the given surface gap, approaching at speed (< 0: separating),
  !> classified; bound (when given) checks the energy test itself for that state.
  subroutine expect(name, collided, gap, speed, outcome, settled, bound)
    character(len=*), intent(in) :: name, outcome
    logical, intent(in) :: collided, settled
    real(wp), intent(in) :: gap, speed
    logical, intent(in), optional :: bound
    type(rigid_body_t) :: body1, body2
    type(closest_points_t) :: contact
    type(pair_outcome_t) :: result
    real(wp), parameter :: q0(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
    call rigid_body_of_spheroid(body1, sphere, [0.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[0.5_wp * speed, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(body2, sphere, [2.0_wp * radius + gap, 0.0_wp, 0.0_wp], q0, &
                                velocity=[-0.5_wp * speed, 0.0_wp, 0.0_wp])
    call find_closest_points(sphere, body1%position, body1%quaternion, sphere, body2%position, body2%quaternion, contact)
    result = pair_outcome_of(rules, collided, body1, body2, contact, 1.0_wp)
    call check(result%outcome == outcome, name//'_outcome', 'got '//trim(result%outcome)//', expected '//outcome)
    call check(result%settled .eqv. settled, name//'_settled')
    if (present(bound)) call check((relative_normal_energy(body1, body2, contact) &
                                    < escape_energy(models%dlvo_model, contact%gap, 1.0_wp)) .eqv. bound, name//'_bound')
  end subroutine expect

end program test_pair_outcome
