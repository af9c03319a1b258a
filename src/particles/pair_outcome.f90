!> The outcome of a particle pair and whether it is settled (docs/theory.md, "Run outcome").
!>  - agglomerated: the pair has collided, is within the range of the DLVO well (gap <= dlvo_range:
!>    60 Debye lengths, module dlvo) and is bound by energy: mu v_n^2 / 2 of the closest points'
!>    normal motion (reduced mass mu) is below the energy needed to escape from the current gap
!>    (escape_energy, at the current chi_eta);
!>  - rebounded: collided, not agglomerated;
!>  - no_contact: never collided.
!> Settled means nothing but a new collision can change it any more:
!>  - an agglomerate in contact (gap <= contact_gap: the vdW cut-off of the DLVO model, where the
!>    surfaces are in molecular contact, and at least the collision detection floor);
!>  - any other pair beyond the DLVO range and not approaching (v_n <= 0).
!> Everything else (a pair inside the well, or approaching from beyond it) is in flight: its outcome
!> is what it would be if the run stopped now.
module pair_outcome
  use agglo_kinds, only: wp
  use rigid_body, only: rigid_body_t
  use closest_points, only: closest_points_t
  use dlvo, only: dlvo_model_t, dlvo_range, relative_normal_energy, escape_energy
  use collision, only: approach_speed
  use particle_system, only: particle_models_t
  implicit none
  private
  public :: pair_outcome_t, pair_outcome_rules_t, pair_outcome_rules_of, pair_outcome_of

  type :: pair_outcome_t
    character(len=16) :: outcome = ''     !< 'agglomerated' | 'rebounded' | 'no_contact'
    logical :: settled = .false.
  end type pair_outcome_t

  !> What the outcome test needs from the models.
  type :: pair_outcome_rules_t
    logical :: dlvo = .false.             !< without DLVO there is no well: nothing agglomerates
    type(dlvo_model_t) :: dlvo_model
    real(wp) :: dlvo_range = 0.0_wp       !< m, range of the well (0 without DLVO)
    real(wp) :: contact_gap = 0.0_wp      !< m, in contact at or below this gap
  end type pair_outcome_rules_t

contains

  pure function pair_outcome_rules_of(models) result(rules)
    type(particle_models_t), intent(in) :: models
    type(pair_outcome_rules_t) :: rules
    rules%dlvo = models%dlvo
    if (models%dlvo) then
      rules%dlvo_model = models%dlvo_model
      rules%dlvo_range = dlvo_range(models%dlvo_model)
      rules%contact_gap = models%dlvo_model%vdw_cutoff
    end if
    if (models%collisions) rules%contact_gap = max(rules%contact_gap, models%collision_model%detection_floor)
  end function pair_outcome_rules_of

  !> Outcome of a pair in its current state. collided: at least one collision so far; body2: the
  !> second body at its minimum image; contact: current closest points; chi_eta: current curvature factor.
  pure function pair_outcome_of(rules, collided, body1, body2, contact, chi_eta) result(outcome)
    type(pair_outcome_rules_t), intent(in) :: rules
    logical, intent(in) :: collided
    type(rigid_body_t), intent(in) :: body1, body2
    type(closest_points_t), intent(in) :: contact
    real(wp), intent(in) :: chi_eta
    type(pair_outcome_t) :: outcome
    logical :: bound, within_range
    within_range = rules%dlvo .and. contact%gap <= rules%dlvo_range
    bound = .false.
    if (within_range) bound = relative_normal_energy(body1, body2, contact) &
                              < escape_energy(rules%dlvo_model, contact%gap, chi_eta)
    if (collided .and. within_range .and. bound) then
      outcome%outcome = 'agglomerated'
      outcome%settled = contact%gap <= rules%contact_gap
    else
      if (collided) then
        outcome%outcome = 'rebounded'
      else
        outcome%outcome = 'no_contact'
      end if
      outcome%settled = contact%gap > rules%dlvo_range .and. &
          approach_speed(body1, body2, contact%point1, contact%point2, contact%normal) <= 0.0_wp
    end if
  end function pair_outcome_of
end module pair_outcome
