!> The bonds of a many-body system as it runs, their formation and breakage events, and the contact
!> episodes begun per species pair (docs/theory.md, "Agglomerates"); the clusters of an instant are
!> the connected components of its bonds (module agglomerates).
!>
!> Bond rule: a pair of the system's near-pair records is bonded when its closest points are current
!> and module pair_outcome says it is bound in the DLVO well (pair_state_of):
!>   E = mu v_n^2 / 2 + U(h) < U_b(h)  and  h <= h_r,
!> touching or not. A pair without a record (beyond the broad phase's gap) is not bonded.
!> agglomerate_tracker_update evaluates the rule for every record at the state the system holds (the
!> scene loop calls it after every particle step, so events carry the step's time); a pair that
!> turns bound is a formation event, a bonded pair that is no longer bound (or lost its record) a
!> breakage event. Each event records the pair, the parametric angles (theta, phi) of the closest
!> point on each body (closest_points), the approach speed of the closest points (> 0 approaching)
!> and the gap; a pair that lost its record is reported with the last values it was seen with.
!>
!> Bond images: a bond formed now takes the minimum image of its second body next to the first
!> (bond_image); at every later update the image is carried across the bodies' box crossings since
!> (carried_bond_image with the change of particle_system's wraps), so it stays true while a cluster
!> drifts across the periodic boundary.
!>
!> Collision counts: agglomerate_count_contact adds one contact episode begun between two bodies to
!> the count of their species pair (species s <= s', numbered (1,1), (1,2), ..., (1,S), (2,2), ...).
!>
!> The events wait in the tracker until the output takes them (agglomerate_take_events). The state
!> that continues a run bit for bit (bonds, images, the wraps they were carried at, formation times,
!> last values, event and collision counters) is the checkpoint group 'agglomerates'.
module agglomerate_tracking
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use text_format, only: int_text
  use hdf5_files, only: h5_exists
  use hdf5_datasets, only: h5_write_array, h5_read_array
  use checkpoint_files, only: checkpoint_t
  use particle_system, only: particle_system_t, particle_pair_t, pair_body_image
  use pair_outcome, only: pair_outcome_rules_t, pair_outcome_rules_of, pair_state_t, pair_state_of
  use agglomerates, only: bond_t, bond_image, carried_bond_image
  implicit none
  private
  public :: tracked_bond_t, bond_event_t, agglomerate_tracker_t, agglomerate_tracker_create, &
            agglomerate_tracker_update, agglomerate_count_contact, agglomerate_bonds, agglomerate_take_events, &
            species_pair_index, species_pairs, write_agglomerate_checkpoint, read_agglomerate_checkpoint, &
            event_formed, event_broken

  integer, parameter :: event_formed = 1, event_broken = 2

  !> One bond: body second at its image (periods) is bonded to body first, first < second.
  type :: tracked_bond_t
    integer :: first = 0, second = 0
    integer :: image(3) = 0                  !< periods of second next to first, true at the wraps below
    integer(i8) :: wraps_first(3) = 0_i8     !< the bodies' wraps when the image was last carried
    integer(i8) :: wraps_second(3) = 0_i8
    real(wp) :: since = 0.0_wp               !< s, formation time
    !> the last evaluated state: closest-point angles on each body (rad), approach speed (m/s), gap (m)
    real(wp) :: theta(2) = 0.0_wp, phi(2) = 0.0_wp, normal_speed = 0.0_wp, gap = 0.0_wp
  end type tracked_bond_t

  !> A bond formed (kind event_formed) or broken (event_broken).
  type :: bond_event_t
    real(wp) :: time = 0.0_wp                !< s
    integer :: kind = 0
    integer :: pair(2) = 0                   !< bodies, first < second
    real(wp) :: theta(2) = 0.0_wp, phi(2) = 0.0_wp   !< rad, closest point on each body (body frame)
    real(wp) :: normal_speed = 0.0_wp        !< m/s, > 0 approaching
    real(wp) :: gap = 0.0_wp                 !< m
  end type bond_event_t

  type :: agglomerate_tracker_t
    type(pair_outcome_rules_t) :: rules
    integer :: species = 1                            !< S species
    integer, allocatable :: species_of(:)             !< (n) species of each body, 1..S
    type(tracked_bond_t), allocatable :: bonds(:)     !< sorted by (first, second)
    type(bond_event_t), allocatable :: events(:)      !< events not yet taken by the output
    integer :: pending = 0                            !< events(1:pending)
    integer(i8) :: formed = 0_i8, broken = 0_i8       !< events since t = 0
    integer(i8), allocatable :: collisions(:)         !< (S (S + 1) / 2) contact episodes begun per species pair
  end type agglomerate_tracker_t

contains

  !> A tracker of the system's bonds (none yet); species_of: the species of each body (1..species).
  subroutine agglomerate_tracker_create(tracker, system, species_of, species)
    type(agglomerate_tracker_t), intent(out) :: tracker
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: species_of(:), species
    if (size(species_of) /= system%n .or. any(species_of < 1) .or. any(species_of > species)) &
      call fatal('agglomerate_tracking: one species in 1..'//int_text(species)//' per body is required')
    tracker%rules = pair_outcome_rules_of(system%models)
    tracker%species = species
    tracker%species_of = species_of
    allocate(tracker%bonds(0), tracker%events(16))
    allocate(tracker%collisions(species * (species + 1) / 2))
    tracker%collisions = 0_i8
  end subroutine agglomerate_tracker_create

  !> Position of species pair (s, t) in the list (1,1), (1,2), ..., (1,S), (2,2), ..., (S,S).
  pure integer function species_pair_index(species, s, t)
    integer, intent(in) :: species, s, t
    integer :: low, high
    low = min(s, t)
    high = max(s, t)
    species_pair_index = (low - 1) * species - (low - 1) * (low - 2) / 2 + high - low + 1
  end function species_pair_index

  !> The species pairs (2, S (S + 1) / 2), first <= second, in the order of species_pair_index.
  pure function species_pairs(species) result(pairs)
    integer, intent(in) :: species
    integer :: pairs(2, species * (species + 1) / 2)
    integer :: s, t, k
    k = 0
    do s = 1, species
      do t = s, species
        k = k + 1
        pairs(:, k) = [s, t]
      end do
    end do
  end function species_pairs

  !> One contact episode begun between bodies first and second.
  subroutine agglomerate_count_contact(tracker, first, second)
    type(agglomerate_tracker_t), intent(inout) :: tracker
    integer, intent(in) :: first, second
    integer :: k
    k = species_pair_index(tracker%species, tracker%species_of(first), tracker%species_of(second))
    tracker%collisions(k) = tracker%collisions(k) + 1_i8
  end subroutine agglomerate_count_contact

  !> The bond rule on every pair record of the system's current state at time (s): the new bond list,
  !> with an event for every bond formed or broken. Both lists are sorted by (first, second): one merge.
  subroutine agglomerate_tracker_update(tracker, system, time)
    type(agglomerate_tracker_t), intent(inout) :: tracker
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: time
    type(tracked_bond_t), allocatable :: kept(:)
    type(tracked_bond_t) :: bond
    type(pair_state_t) :: state
    integer :: p, old, count
    allocate(kept(size(tracker%bonds) + size(system%pairs)))
    count = 0
    old = 1
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p))
        ! Bonds of pairs before this record have lost their records: broken.
        do while (old <= size(tracker%bonds))
          if (before(tracker%bonds(old), pair%first, pair%second)) then
            call add_event(tracker, time, event_broken, tracker%bonds(old))
            old = old + 1
          else
            exit
          end if
        end do
        state = pair_state_t()
        if (pair%active) state = pair_state_of(tracker%rules, system%bodies(pair%first), pair_body_image(system, pair), &
                                               pair%contact, pair%dlvo%chi_eta)
        bond = tracked_bond_t()
        if (old <= size(tracker%bonds)) then
          if (tracker%bonds(old)%first == pair%first .and. tracker%bonds(old)%second == pair%second) then
            bond = tracker%bonds(old)
            old = old + 1
          end if
        end if
        if (bond%first > 0) then            ! bonded before
          if (state%bound) then
            call carry(bond, system)
            call observe(bond, pair, state)
            count = count + 1
            kept(count) = bond
          else
            if (pair%active) call observe(bond, pair, state)
            call add_event(tracker, time, event_broken, bond)
          end if
        else if (state%bound) then          ! formed now
          bond%first = pair%first
          bond%second = pair%second
          bond%image = bond_image(system%bodies(pair%first)%position, system%bodies(pair%second)%position, &
                                  system%box_length)
          bond%wraps_first = system%wraps(:, pair%first)
          bond%wraps_second = system%wraps(:, pair%second)
          bond%since = time
          call observe(bond, pair, state)
          call add_event(tracker, time, event_formed, bond)
          count = count + 1
          kept(count) = bond
        end if
      end associate
    end do
    do while (old <= size(tracker%bonds))
      call add_event(tracker, time, event_broken, tracker%bonds(old))
      old = old + 1
    end do
    tracker%bonds = kept(1:count)
  end subroutine agglomerate_tracker_update

  pure logical function before(bond, first, second)
    type(tracked_bond_t), intent(in) :: bond
    integer, intent(in) :: first, second
    before = bond%first < first .or. (bond%first == first .and. bond%second < second)
  end function before

  !> The bond's image carried across the crossings of its bodies since it was last carried.
  pure subroutine carry(bond, system)
    type(tracked_bond_t), intent(inout) :: bond
    type(particle_system_t), intent(in) :: system
    bond%image = carried_bond_image(bond%image, system%wraps(:, bond%first) - bond%wraps_first, &
                                    system%wraps(:, bond%second) - bond%wraps_second)
    bond%wraps_first = system%wraps(:, bond%first)
    bond%wraps_second = system%wraps(:, bond%second)
  end subroutine carry

  !> The pair's current closest-point angles, approach speed and gap, kept with the bond.
  pure subroutine observe(bond, pair, state)
    type(tracked_bond_t), intent(inout) :: bond
    type(particle_pair_t), intent(in) :: pair
    type(pair_state_t), intent(in) :: state
    bond%theta = [pair%contact%theta1, pair%contact%theta2]
    bond%phi = [pair%contact%phi1, pair%contact%phi2]
    bond%normal_speed = state%approach_speed
    bond%gap = state%gap
  end subroutine observe

  subroutine add_event(tracker, time, kind, bond)
    type(agglomerate_tracker_t), intent(inout) :: tracker
    real(wp), intent(in) :: time
    integer, intent(in) :: kind
    type(tracked_bond_t), intent(in) :: bond
    type(bond_event_t), allocatable :: grown(:)
    if (tracker%pending == size(tracker%events)) then
      allocate(grown(2 * size(tracker%events)))
      grown(1:tracker%pending) = tracker%events(1:tracker%pending)
      call move_alloc(grown, tracker%events)
    end if
    tracker%pending = tracker%pending + 1
    tracker%events(tracker%pending) = bond_event_t(time=time, kind=kind, pair=[bond%first, bond%second], &
        theta=bond%theta, phi=bond%phi, normal_speed=bond%normal_speed, gap=bond%gap)
    if (kind == event_formed) then
      tracker%formed = tracker%formed + 1_i8
    else
      tracker%broken = tracker%broken + 1_i8
    end if
  end subroutine add_event

  !> The events since the last call (oldest first); the tracker forgets them.
  subroutine agglomerate_take_events(tracker, events)
    type(agglomerate_tracker_t), intent(inout) :: tracker
    type(bond_event_t), allocatable, intent(out) :: events(:)
    events = tracker%events(1:tracker%pending)
    tracker%pending = 0
  end subroutine agglomerate_take_events

  !> The current bonds as the agglomerate analysis takes them (module agglomerates).
  pure function agglomerate_bonds(tracker) result(bonds)
    type(agglomerate_tracker_t), intent(in) :: tracker
    type(bond_t), allocatable :: bonds(:)
    integer :: b
    allocate(bonds(size(tracker%bonds)))
    do b = 1, size(bonds)
      bonds(b) = bond_t(first=tracker%bonds(b)%first, second=tracker%bonds(b)%second, image=tracker%bonds(b)%image)
    end do
  end function agglomerate_bonds

  !> The group 'agglomerates' of an open checkpoint (collective: rank 0's values written). Taken
  !> events must have been written out first (the checkpoint keeps none waiting). Datasets:
  !> bonds (11, B) integer (first, second, image(3), wraps_first(3), wraps_second(3) as integers),
  !> bond_values (8, B) (since, theta(2), phi(2), normal_speed, gap, 0), counters (2 + P) integer(i8)
  !> (formed, broken, collisions per species pair). A leading zero column keeps B = 0 non-empty.
  subroutine write_agglomerate_checkpoint(checkpoint, tracker)
    type(checkpoint_t), intent(in) :: checkpoint
    type(agglomerate_tracker_t), intent(in) :: tracker
    integer(i8), allocatable :: integers(:,:)
    real(wp), allocatable :: values(:,:)
    integer :: b
    if (tracker%pending > 0) call fatal('agglomerate_tracking: a checkpoint with events not yet written out')
    allocate(integers(11, 0:size(tracker%bonds)), values(8, 0:size(tracker%bonds)))
    integers = 0_i8
    values = 0.0_wp
    do b = 1, size(tracker%bonds)
      associate (bond => tracker%bonds(b))
        integers(:, b) = [int(bond%first, i8), int(bond%second, i8), int(bond%image, i8), bond%wraps_first, &
                          bond%wraps_second]
        values(:, b) = [bond%since, bond%theta, bond%phi, bond%normal_speed, bond%gap, 0.0_wp]
      end associate
    end do
    call h5_write_array(checkpoint%file, 'agglomerates/bonds', integers)
    call h5_write_array(checkpoint%file, 'agglomerates/bond_values', values)
    call h5_write_array(checkpoint%file, 'agglomerates/counters', [tracker%formed, tracker%broken, tracker%collisions])
  end subroutine write_agglomerate_checkpoint

  !> Restore the tracker (created for the same system and species) from an open checkpoint.
  subroutine read_agglomerate_checkpoint(checkpoint, tracker)
    type(checkpoint_t), intent(in) :: checkpoint
    type(agglomerate_tracker_t), intent(inout) :: tracker
    integer(i8), allocatable :: integers(:,:), counters(:)
    real(wp), allocatable :: values(:,:)
    integer :: b, m
    if (.not. h5_exists(checkpoint%file, 'agglomerates/bonds')) call fatal('checkpoint '//checkpoint%path// &
        ' holds no bonds (group agglomerates): written by a run without agglomerate tracking?')
    call h5_read_array(checkpoint%file, 'agglomerates/bonds', integers)
    call h5_read_array(checkpoint%file, 'agglomerates/bond_values', values)
    call h5_read_array(checkpoint%file, 'agglomerates/counters', counters)
    m = size(integers, 2) - 1
    if (size(integers, 1) /= 11 .or. any(shape(values) /= [8, m + 1]) .or. &
        size(counters) /= 2 + size(tracker%collisions)) &
      call fatal('checkpoint '//checkpoint%path//': its agglomerates group does not fit this scene')
    deallocate(tracker%bonds)
    allocate(tracker%bonds(m))
    do b = 1, m
      associate (bond => tracker%bonds(b), k => integers(:, b + 1), v => values(:, b + 1))
        bond%first = int(k(1))
        bond%second = int(k(2))
        bond%image = int(k(3:5))
        bond%wraps_first = k(6:8)
        bond%wraps_second = k(9:11)
        bond%since = v(1)
        bond%theta = v(2:3)
        bond%phi = v(4:5)
        bond%normal_speed = v(6)
        bond%gap = v(7)
      end associate
    end do
    tracker%formed = counters(1)
    tracker%broken = counters(2)
    tracker%collisions = counters(3:)
    tracker%pending = 0
  end subroutine read_agglomerate_checkpoint
end module agglomerate_tracking
