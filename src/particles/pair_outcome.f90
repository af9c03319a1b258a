!> The outcome of a particle pair by its mechanical state, whether it is settled, and the record of
!> contact the outcome keeps beside it (docs/theory.md, "Run outcome").
!> Bound: the gap is inside the range of the DLVO well (h <= h_r = dlvo_range: 60 Debye lengths) and
!>   E = mu v_n^2 / 2 + U(h) < U_b(h) = max(0, max_{h' >= h} U(h'))
!> (mu the reduced mass, v_n the normal speed of the closest points, U the DLVO energy at the current
!> chi_eta, U_b the barrier, or the range's edge U -> 0 where there is none): the normal motion has not
!> the energy to leave the well (escape_energy = U_b - U). Escaped: not bound. Classes:
!>  - agglomerated: bound, touched or not;
!>  - rebounded: escaped after at least one contact episode;
!>  - approached: escaped, never touched, but inside the DLVO range at some recorded state;
!>  - no_contact: never inside the range (so never touched).
!> Settled means the outcome no longer changes unless something new happens:
!>  - agglomerated: bound without a break for at least settle_time (&pair settle_time);
!>  - any other class: beyond the DLVO range and not approaching (v_n <= 0).
!> Everything else is in flight: its outcome is what it would be if the run stopped now.
!> A contact episode begins at an impulse after the pair has been apart by more than the release gap
!> (or at its first impulse) and ends when the gap exceeds it (release_gap, below).
module pair_outcome
  use agglo_kinds, only: wp
  use rigid_body, only: rigid_body_t
  use closest_points, only: closest_points_t
  use dlvo, only: dlvo_model_t, dlvo_range, dlvo_energy, relative_normal_energy, escape_energy
  use collision, only: approach_speed
  use particle_system, only: particle_models_t
  implicit none
  private
  public :: pair_outcome_t, pair_outcome_rules_t, pair_state_t, pair_history_t, pair_outcome_rules_of, &
            pair_state_of, pair_history_record, pair_outcome_of, pair_outcome_classes

  !> Every class summary.json may carry, in the order of the tables of tools/agglo-stats.
  character(len=12), parameter :: pair_outcome_classes(4) = [character(len=12) :: 'agglomerated', 'rebounded', &
                                                             'approached', 'no_contact']

  type :: pair_outcome_t
    character(len=16) :: outcome = ''     !< one of pair_outcome_classes
    logical :: settled = .false.
  end type pair_outcome_t

  !> What the outcome test needs from the models and the deck.
  type :: pair_outcome_rules_t
    logical :: dlvo = .false.             !< without DLVO there is no well: nothing is bound
    type(dlvo_model_t) :: dlvo_model
    real(wp) :: dlvo_range = 0.0_wp       !< m, range of the well h_r (0 without DLVO)
    !> m, a contact episode ends when the gap exceeds this: the vdW cut-off (molecular contact, where
    !> the vdW force is capped) and at least twice the collision detection floor, so the chatter of a
    !> resting contact held at the floor (excursions of a fraction of the floor) never ends it
    real(wp) :: release_gap = 0.0_wp
    real(wp) :: settle_time = 0.0_wp      !< s, bound this long: agglomerated and settled
  end type pair_outcome_rules_t

  !> The pair's mechanical state now (pair_state_of).
  type :: pair_state_t
    real(wp) :: gap = huge(1.0_wp)        !< m
    real(wp) :: approach_speed = 0.0_wp   !< m/s, v_n of the closest points, > 0 approaching
    logical :: in_range = .false.         !< gap <= dlvo_range (DLVO on)
    logical :: bound = .false.            !< in range and E < U_b
  end type pair_state_t

  !> What the pair has done so far: kept by the scene from step to step (and in its checkpoints).
  type :: pair_history_t
    logical :: touched = .false.          !< at least one contact episode
    logical :: entered_range = .false.    !< inside the DLVO range at some recorded state
    logical :: bound = .false.            !< bound at the last recorded state
    real(wp) :: bound_since = 0.0_wp      !< s, start of the unbroken bound stretch (when bound)
  end type pair_history_t

contains

  !> The rules of the models; settle_time: &pair settle_time (s; absent: 0, bound now is settled).
  pure function pair_outcome_rules_of(models, settle_time) result(rules)
    type(particle_models_t), intent(in) :: models
    real(wp), intent(in), optional :: settle_time
    type(pair_outcome_rules_t) :: rules
    rules%dlvo = models%dlvo
    if (models%dlvo) then
      rules%dlvo_model = models%dlvo_model
      rules%dlvo_range = dlvo_range(models%dlvo_model)
      rules%release_gap = models%dlvo_model%vdw_cutoff
    end if
    if (models%collisions) rules%release_gap = max(rules%release_gap, 2.0_wp * models%collision_model%detection_floor)
    if (present(settle_time)) rules%settle_time = settle_time
  end function pair_outcome_rules_of

  !> The state of a pair: body2 at its minimum image, contact its current closest points, chi_eta
  !> the current curvature factor. E < U_b is decided without the barrier search when E < 0 (U_b >= 0),
  !> exactly as mu v_n^2 / 2 < escape_energy would decide it.
  pure function pair_state_of(rules, body1, body2, contact, chi_eta) result(state)
    type(pair_outcome_rules_t), intent(in) :: rules
    type(rigid_body_t), intent(in) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    real(wp), intent(in) :: chi_eta
    type(pair_state_t) :: state
    real(wp) :: kinetic
    state%gap = contact%gap
    state%approach_speed = approach_speed(body1, body2, contact%point1, contact%point2, contact%normal)
    state%in_range = rules%dlvo .and. contact%gap <= rules%dlvo_range
    if (.not. state%in_range) return
    kinetic = relative_normal_energy(body1, body2, contact)
    if (kinetic + dlvo_energy(rules%dlvo_model, contact%gap, chi_eta) < 0.0_wp) then
      state%bound = .true.
    else
      state%bound = kinetic < escape_energy(rules%dlvo_model, contact%gap, chi_eta)
    end if
  end function pair_state_of

  !> Add the state at time (s) to the record; touched: the pair has had a contact episode by now.
  pure subroutine pair_history_record(history, state, touched, time)
    type(pair_history_t), intent(inout) :: history
    type(pair_state_t), intent(in) :: state
    logical, intent(in) :: touched
    real(wp), intent(in) :: time
    history%touched = history%touched .or. touched
    history%entered_range = history%entered_range .or. state%in_range
    if (state%bound .and. .not. history%bound) history%bound_since = time
    history%bound = state%bound
  end subroutine pair_history_record

  !> The outcome of a pair whose record (history, with the current state already added) and current
  !> state are given, at time (s).
  pure function pair_outcome_of(rules, history, state, time) result(outcome)
    type(pair_outcome_rules_t), intent(in) :: rules
    type(pair_history_t), intent(in) :: history
    type(pair_state_t), intent(in) :: state
    real(wp), intent(in) :: time
    type(pair_outcome_t) :: outcome
    if (state%bound) then
      outcome%outcome = 'agglomerated'
      ! A relative margin of 1e-12: the times are sums of steps (round-off), the hold a deck value.
      outcome%settled = history%bound .and. time - history%bound_since >= rules%settle_time * (1.0_wp - 1.0e-12_wp)
      return
    end if
    if (history%touched) then
      outcome%outcome = 'rebounded'
    else if (history%entered_range .or. state%in_range) then
      outcome%outcome = 'approached'
    else
      outcome%outcome = 'no_contact'
    end if
    outcome%settled = state%gap > rules%dlvo_range .and. state%approach_speed <= 0.0_wp
  end function pair_outcome_of
end module pair_outcome
