! checks: 53
!> Unit tests of pair_outcome (docs/theory.md, "Run outcome"): two calcite spheres (r = 50 um, the
!> paper's Table 1 DLVO constants: Debye length 3.04 nm, so the DLVO range is 60 of them, 182 nm)
!> in the states that separate bound from escaped, then the classes and their settling on
!> constructed records: each class, and the boundaries of the energy, the range, the approach speed
!> and the settle time.
program test_pair_outcome
  use agglo_kinds, only: wp
  use config_dlvo, only: dlvo_config_t
  use config_collision, only: collision_config_t
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid
  use closest_points, only: closest_points_t, find_closest_points
  use dlvo, only: dlvo_setup, escape_energy, relative_normal_energy, dlvo_energy
  use collision, only: collision_setup
  use particle_system, only: particle_models_t
  use pair_outcome, only: pair_outcome_t, pair_outcome_rules_t, pair_outcome_rules_of, pair_outcome_of, pair_state_t, &
                          pair_state_of, pair_history_t, pair_history_record
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none
  real(wp), parameter :: radius = 50.0e-6_wp, density = 2710.0_wp, settle = 1.0e-3_wp
  type(particle_models_t) :: models, hard_only
  type(pair_outcome_rules_t) :: rules, no_dlvo
  type(spheroid_t) :: sphere
  real(wp) :: mu, critical, range

  call test_start('pair_outcome')
  sphere = make_spheroid('sphere', radius, density)
  models%dlvo = .true.
  call dlvo_setup(models%dlvo_model, dlvo_config_t(), radius)
  models%collisions = .true.
  call collision_setup(models%collision_model, collision_config_t())
  rules = pair_outcome_rules_of(models, settle)
  range = rules%dlvo_range
  ! 60 Debye lengths, 1/kappa = 1 / 328947368 m (Table 1).
  call check_close(range, 60.0_wp / 328947368.0_wp, 1.0e-12_wp, 'dlvo_range_is_60_debye_lengths')
  ! Release gap: the 5 nm vdW cut-off (above twice the 1 nm detection floor); without DLVO twice the floor.
  call check_close(rules%release_gap, 5.0e-9_wp, 1.0e-12_wp, 'release_gap_is_the_vdw_cutoff')
  hard_only%collisions = .true.
  call collision_setup(hard_only%collision_model, collision_config_t())
  no_dlvo = pair_outcome_rules_of(hard_only)
  call check_close(no_dlvo%release_gap, 2.0e-9_wp, 1.0e-12_wp, 'release_gap_without_dlvo_is_two_floors')
  call check_close(rules%settle_time, settle, 1.0e-15_wp, 'settle_time_from_the_deck')

  ! --- bound or escaped, from the bodies' state (pair_state_of) ---
  ! The Stokes pair stopped by the drag 0.92 um apart after a collision: no kinetic energy, U < 0,
  ! but outside the range: not bound (the energy test alone would call it bound).
  call expect_state('stopped_far_apart', 0.92e-6_wp, 0.0_wp, in_range=.false., bound=.false.)
  call expect_state('resting_in_contact', 1.0e-9_wp, 0.0_wp, in_range=.true., bound=.true.)
  ! 50 nm apart inside the well: separating at 1e-5 m/s bound, at 1 mm/s (mu v^2 / 2 far above the
  ! escape energy) escaped; approaching at 1 mm/s is escaped as well (the energy, not the direction).
  call expect_state('inside_well_slow', 50.0e-9_wp, -1.0e-5_wp, in_range=.true., bound=.true.)
  call expect_state('inside_well_fast', 50.0e-9_wp, -1.0e-3_wp, in_range=.true., bound=.false.)
  call expect_state('inside_well_fast_approaching', 50.0e-9_wp, 1.0e-3_wp, in_range=.true., bound=.false.)
  ! The energy boundary: mu v*^2 / 2 = escape_energy(h) at 50 nm; 1e-6 either side of v*.
  mu = 0.5_wp * sphere%mass
  critical = sqrt(2.0_wp * escape_energy(models%dlvo_model, 50.0e-9_wp, 1.0_wp) / mu)
  call expect_state('just_below_escape_speed', 50.0e-9_wp, -critical * (1.0_wp - 1.0e-6_wp), in_range=.true., &
                    bound=.true.)
  call expect_state('just_above_escape_speed', 50.0e-9_wp, -critical * (1.0_wp + 1.0e-6_wp), in_range=.true., &
                    bound=.false.)
  ! The range boundary: at rest (U < 0 on both sides) bound just inside, not just outside.
  call expect_state('at_rest_just_inside_range', range * (1.0_wp - 1.0e-6_wp), 0.0_wp, in_range=.true., bound=.true.)
  call expect_state('at_rest_just_outside_range', range * (1.0_wp + 1.0e-6_wp), 0.0_wp, in_range=.false., &
                    bound=.false.)

  ! --- the classes and their settling, on constructed records ---
  ! agglomerated: bound, with contact and without.
  call expect_class('agglomerated_touched', touched=.true., entered=.true., bound_for=2.0_wp * settle, &
                    gap=1.0e-9_wp, speed=0.0_wp, outcome='agglomerated', settled=.true.)
  call expect_class('agglomerated_without_contact', touched=.false., entered=.true., bound_for=2.0_wp * settle, &
                    gap=40.0e-9_wp, speed=-1.0e-6_wp, outcome='agglomerated', settled=.true.)
  ! Settling of a bound pair: the hold just short of settle_time, then reached.
  call expect_class('bound_just_short_of_settle_time', touched=.true., entered=.true., &
                    bound_for=settle * (1.0_wp - 1.0e-6_wp), gap=1.0e-9_wp, speed=0.0_wp, outcome='agglomerated', &
                    settled=.false.)
  call expect_class('bound_for_settle_time', touched=.true., entered=.true., bound_for=settle, gap=1.0e-9_wp, &
                    speed=0.0_wp, outcome='agglomerated', settled=.true.)
  ! rebounded: touched, escaped; settled beyond the range and separating, in flight inside it.
  call expect_class('rebounded_gone', touched=.true., entered=.true., bound_for=-1.0_wp, gap=1.0e-6_wp, &
                    speed=-1.0e-3_wp, outcome='rebounded', settled=.true.)
  call expect_class('rebounded_inside_range', touched=.true., entered=.true., bound_for=-1.0_wp, gap=50.0e-9_wp, &
                    speed=-1.0e-3_wp, outcome='rebounded', settled=.false.)
  ! approached: in the range once, never touched, escaped.
  call expect_class('approached_gone', touched=.false., entered=.true., bound_for=-1.0_wp, gap=1.0e-6_wp, &
                    speed=-1.0e-4_wp, outcome='approached', settled=.true.)
  call expect_class('approached_inside_range', touched=.false., entered=.true., bound_for=-1.0_wp, gap=100.0e-9_wp, &
                    speed=1.0e-3_wp, outcome='approached', settled=.false.)
  ! no_contact: never in the range; settled only beyond it and not approaching (v_n = 0 is not).
  call expect_class('no_contact_at_rest', touched=.false., entered=.false., bound_for=-1.0_wp, gap=3.0e-6_wp, &
                    speed=0.0_wp, outcome='no_contact', settled=.true.)
  call expect_class('no_contact_approaching', touched=.false., entered=.false., bound_for=-1.0_wp, gap=3.0e-6_wp, &
                    speed=1.0e-4_wp, outcome='no_contact', settled=.false.)
  ! The range's edge itself is inside: separating from exactly h_r is not yet settled.
  call expect_class('escaped_at_the_range_edge', touched=.true., entered=.true., bound_for=-1.0_wp, gap=range, &
                    speed=-1.0e-3_wp, outcome='rebounded', settled=.false.)

  call bound_stretch_restarts()
  call test_finish()

contains

  !> Two spheres on the x axis at the given surface gap, approaching at speed (< 0: separating):
  !> their state; bound agrees with mu v_n^2 / 2 < escape_energy whenever in range.
  subroutine expect_state(name, gap, speed, in_range, bound)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: gap, speed
    logical, intent(in) :: in_range, bound
    type(rigid_body_t) :: body1, body2
    type(closest_points_t) :: contact
    type(pair_state_t) :: state
    real(wp), parameter :: q0(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]
    call rigid_body_of_spheroid(body1, sphere, [0.0_wp, 0.0_wp, 0.0_wp], q0, velocity=[0.5_wp * speed, 0.0_wp, 0.0_wp])
    call rigid_body_of_spheroid(body2, sphere, [2.0_wp * radius + gap, 0.0_wp, 0.0_wp], q0, &
                                velocity=[-0.5_wp * speed, 0.0_wp, 0.0_wp])
    call find_closest_points(sphere, body1%position, body1%quaternion, sphere, body2%position, body2%quaternion, contact)
    state = pair_state_of(rules, body1, body2, contact, 1.0_wp)
    call check(state%in_range .eqv. in_range, name//'_in_range')
    call check(state%bound .eqv. bound, name//'_bound')
    if (in_range) call check(state%bound .eqv. (relative_normal_energy(body1, body2, contact) &
        < escape_energy(models%dlvo_model, contact%gap, 1.0_wp)), name//'_bound_is_the_escape_test', &
        'E = '//energy_text(relative_normal_energy(body1, body2, contact) &
        + dlvo_energy(models%dlvo_model, contact%gap, 1.0_wp)))
  end subroutine expect_state

  function energy_text(value) result(text)
    real(wp), intent(in) :: value
    character(len=24) :: text
    write(text, '(es12.4,a)') value, ' J'
  end function energy_text

  !> A record built step by step: touched / entered the range as given, bound for bound_for seconds
  !> up to t = 10 ms (< 0: not bound now), and the current state (gap, approach speed).
  subroutine expect_class(name, touched, entered, bound_for, gap, speed, outcome, settled)
    character(len=*), intent(in) :: name, outcome
    logical, intent(in) :: touched, entered, settled
    real(wp), intent(in) :: bound_for, gap, speed
    real(wp), parameter :: now = 10.0e-3_wp
    type(pair_history_t) :: history
    type(pair_state_t) :: earlier, state
    type(pair_outcome_t) :: result
    ! The start: far apart, unbound.
    call pair_history_record(history, pair_state_t(gap=5.0e-6_wp, approach_speed=1.0e-3_wp), .false., 0.0_wp)
    if (entered) then
      earlier = pair_state_t(gap=0.5_wp * range, approach_speed=1.0e-3_wp, in_range=.true., bound=.false.)
      call pair_history_record(history, earlier, touched, 1.0e-3_wp)
    end if
    state = pair_state_t(gap=gap, approach_speed=speed, in_range=gap <= range, bound=bound_for >= 0.0_wp)
    if (bound_for >= 0.0_wp) call pair_history_record(history, state, touched, now - bound_for)
    call pair_history_record(history, state, touched, now)
    result = pair_outcome_of(rules, history, state, now)
    call check(result%outcome == outcome, name//'_outcome', 'got '//trim(result%outcome)//', expected '//outcome)
    call check(result%settled .eqv. settled, name//'_settled')
  end subroutine expect_class

  !> An unbound state between two bound ones starts the bound stretch again: bound 5 ms, unbound
  !> once, bound again for half the settle time is not settled.
  subroutine bound_stretch_restarts()
    type(pair_history_t) :: history
    type(pair_state_t) :: bound, unbound
    type(pair_outcome_t) :: result
    bound = pair_state_t(gap=1.0e-9_wp, approach_speed=0.0_wp, in_range=.true., bound=.true.)
    unbound = pair_state_t(gap=10.0e-9_wp, approach_speed=-1.0e-3_wp, in_range=.true., bound=.false.)
    call pair_history_record(history, bound, .true., 0.0_wp)
    call pair_history_record(history, bound, .true., 5.0e-3_wp)
    call pair_history_record(history, unbound, .true., 5.1e-3_wp)
    call pair_history_record(history, bound, .true., 5.2e-3_wp)
    call pair_history_record(history, bound, .true., 5.2e-3_wp + 0.5_wp * settle)
    result = pair_outcome_of(rules, history, bound, 5.2e-3_wp + 0.5_wp * settle)
    call check(result%outcome == 'agglomerated' .and. .not. result%settled, 'bound_stretch_restarts_after_a_break', &
               trim(result%outcome))
    call check_close(history%bound_since, 5.2e-3_wp, 1.0e-15_wp, 'bound_since_is_the_new_stretch')
  end subroutine bound_stretch_restarts

end program test_pair_outcome
