!> N rigid spheroids, the pairs among them and their one particle step (docs/theory.md, "Particle
!> system"; docs/design.md, data flow step 6).
!>
!> The system owns the bodies (shape, mass, inertia, state), the pair records (closest points kept
!> as the warm start of the next step, the DLVO evaluation, this step's collision) and the loads the
!> pair interactions put on each body. One step of length dt:
!>   1. Newton-Euler update of every body under the external loads of the call (frozen over the
!>      call: Stokes resistance in the pair scenes, resolved hydrodynamic loads later) plus the
!>      DLVO loads of the current state; positions wrapped into the periodic box, if any;
!>   2. with a box, the near pairs of the broad phase (module broad_phase) merged with the last
!>      records; closest points of every pair that may interact (periodic minimum image), warm-started;
!>   3. collision impulses, swept over the contacts in the order of the records (below);
!>   4. DLVO at the closest points, summed per body for the next Newton-Euler update.
!> Steps 2-4 are particle_system_interact, which also prepares a new system (or one read back from
!> a checkpoint), so that between calls the system is always CURRENT: contacts, collision loads and
!> DLVO loads belong to the positions and velocities it holds, which is the state an output, an
!> outcome test, a checkpoint or the next fluid step sees. The per-pair work is recomputed every
!> particle step; nothing pair-related is ever frozen.
!>
!> Pair records, sorted by (i, j): without a box every pair i < j, (1,2), (1,3), ..., (N-1,N); with
!> a box the pairs whose bounding spheres are within the search gap (models%interaction_gap,
!> widened by the collision reach), a pair still near keeping its record across steps. With a gap
!> of huge() both are the full list (the pair scenes: results as they always were). Pairs beyond
!> the gap skip steps 2-4, and so do pairs whose surfaces a lower bound from the support functions
!> puts beyond every model's reach (update_contact); the DLVO force acts where the surface gap is
!> within models%interaction_gap only.
!>
!> Simultaneous impulses (resolve_collisions): in waves of the contacts approaching at the wave's
!> start, each swept in the order of the records until no contact is off its restitution target
!> (projected Gauss-Seidel), then the next wave, at most models%collision_model%max_sweeps sweeps.
!> Three spheres in a line, 1 -> 2 -> 3: the 1-2 impulse, then in the next wave the 2-3 one, the
!> Newton's cradle result, from either end. A pair alone is swept once (the single-pair arithmetic).
!> Every impulse conserves linear and angular momentum and, with e = 1 head-on, energy (to round-off).
!> Optional sub-grid lubrication (module lubrication): after the collisions of step 3, pair by pair
!> in the same order, an impulse implicit in the pair's normal velocity over dt, applied at once;
!> its force (impulse / dt) is kept per body in lubrication_loads for the outputs.
!>
!> Periodic box (box_length > 0 in a direction): bodies live on a torus. A pair is handled with
!> body j moved to its minimum image next to body i (positions, closest points, DLVO lever arms and
!> the impulse all in that frame); body positions are wrapped into [0, L) after each move, and the
!> number of wraps is kept, so unwrapped_position gives the continuous trajectory for statistics.
!> Without a box (the pair scenes) positions are never touched.
module particle_system
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use spheroid, only: spheroid_t
  use rigid_body, only: rigid_body_t, added_inertia_t, rigid_body_step, kinetic_energy
  use closest_points, only: closest_points_t, find_closest_points, gap_lower_bound
  use dlvo, only: dlvo_model_t, dlvo_evaluation_t, dlvo_evaluate, dlvo_cutoff_gap, dlvo_range
  use collision, only: collision_model_t, collision_result_t, collision_detected, collide, approach_speed, &
                       detection_distance, normal_speed_at, normal_correction, regime_frictionless
  use lubrication, only: lubrication_model_t, lubrication_result_t, lubricate
  use vector_algebra, only: cross
  use periodic_box, only: image_shift
  use broad_phase, only: broad_phase_t, broad_phase_find, near_pair
  use logger, only: log_line
  use text_format, only: int_text
  implicit none
  private
  public :: particle_models_t, particle_pair_t, particle_loads_t, particle_system_t, particle_system_create, &
            particle_system_interact, particle_system_step, particle_loads_zero, &
            unwrapped_position, pair_image, pair_body_image, particle_system_energy, particle_system_set_added_inertia, &
            particle_system_set_members, particle_system_all_members
  public :: particle_interaction_gap, bounding_radius, wrap_body, particle_search_gap

  !> The pair models and how the bodies move; set up once by the scene.
  type :: particle_models_t
    logical :: dlvo = .false.                  !< DLVO forces at the closest points
    type(dlvo_model_t) :: dlvo_model
    logical :: collisions = .false.            !< hard-body collision test and impulse
    type(collision_model_t) :: collision_model
    logical :: lubrication = .false.           !< sub-grid lubrication impulse every step
    type(lubrication_model_t) :: lubrication_model
    integer :: integrator = 0                  !< rigid_body integrator code (integrator_euler | integrator_verlet)
    !> Pairs whose bounding spheres are farther apart than this gap (m) skip the per-pair work (no
    !> closest points, no DLVO, no collision). huge(): every pair always interacts (the pair scenes,
    !> where the DLVO force has no cut-off).
    real(wp) :: interaction_gap = huge(1.0_wp)
    !> Ghost collisions (with collisions on): a pair whose surfaces meet within the next step is
    !> counted as a collision, with no impulse (ghost_contacts); the bodies pass through each other.
    logical :: ghost = .false.
  end type particle_models_t

  !> Force and torque (about the centre) on each body, lab frame: (3, N).
  type :: particle_loads_t
    real(wp), allocatable :: force(:,:), torque(:,:)
  end type particle_loads_t

  !> One interacting pair i < j; contact is body i -> the minimum image of body j.
  type :: particle_pair_t
    integer :: first = 0, second = 0
    logical :: active = .false.                !< closest points current (the pair may interact)
    type(closest_points_t) :: contact          !< last closest points: the next warm start
    type(dlvo_evaluation_t) :: dlvo            !< DLVO at the current state (defaults when off/inactive)
    logical :: collided = .false.              !< an impulse was applied in the last interaction
    type(collision_result_t) :: collision      !< that impulse (contact point in the pair's frame)
    type(lubrication_result_t) :: lubrication  !< the last lubrication impulse (inactive above h_out)
  end type particle_pair_t

  type :: particle_system_t
    integer :: n = 0                                     !< number of bodies
    type(spheroid_t), allocatable :: shapes(:)           !< (n)
    type(rigid_body_t), allocatable :: bodies(:)         !< (n): state; positions wrapped when periodic
    integer(i8), allocatable :: wraps(:,:)               !< (3, n): net box crossings, for unwrapped positions
    real(wp) :: box_length(3) = 0.0_wp                   !< m, period per direction; 0 = unbounded
    type(particle_models_t) :: models
    !> The pair records, sorted by (first, second): the order of the sweep. Without a box every pair
    !> i < j (n (n - 1) / 2); with a box the near pairs of the broad phase (near_pairs_only).
    type(particle_pair_t), allocatable :: pairs(:)
    logical :: near_pairs_only = .false.                 !< periodic: pair records only for the near pairs
    real(wp), allocatable :: bounding_radii(:)           !< (n) m, max(a, b): the bodies' bounding spheres
    real(wp) :: search_gap = huge(1.0_wp)                !< m, the broad phase's gap of the last interaction
    type(broad_phase_t) :: finder                        !< cell list of the broad phase (its arrays reused)
    type(particle_loads_t) :: dlvo_loads                 !< summed over pairs, current state
    type(particle_loads_t) :: collision_loads            !< impulse / dt of the last interaction (outputs)
    type(particle_loads_t) :: lubrication_loads          !< lubrication impulse / dt of the last interaction
    integer :: collisions_last = 0                       !< impulses in the last interaction
    integer :: impulse_sweeps_last = 0                   !< sweeps of the last interaction that applied an impulse
    integer :: impulse_sweeps_most = 0                   !< the most such sweeps of one interaction since creation
    integer :: approaching_left = 0                      !< contacts still approaching when the last interaction hit the cap
    integer(i8) :: sweep_caps_total = 0_i8               !< interactions that hit the cap since creation
    integer(i8) :: collisions_total = 0_i8               !< impulses since creation
    !> (n) the fluid's added masses that collision and lubrication impulses move with each body
    !> (module rigid_body, added_inertia_t): zero (bodies alone) unless a coupling that takes the
    !> added mass implicitly sets them (particle_system_set_added_inertia)
    type(added_inertia_t), allocatable :: impulse_added(:)
    logical :: impulses_in_fluid = .false.               !< some impulse_added is non-zero
    !> The bodies the particle steps move, in increasing order, when only some do (a suspension whose
    !> other bodies take the fluid step in one update: particle_system_set_members); not allocated:
    !> every body. The pair records then hold pairs of members only.
    integer, allocatable :: members(:)
    !> Scratch of the steps, kept so that no step allocates: the members' centres and bounding
    !> radii for the broad phase, (3, n) and (n); the impulse clock per body (resolve_collisions).
    real(wp), allocatable :: scratch_positions(:,:), scratch_radii(:)
    integer(i8), allocatable :: touched(:)
  end type particle_system_t

contains

  !> Loads of n bodies, all zero.
  pure function particle_loads_zero(n) result(loads)
    integer, intent(in) :: n
    type(particle_loads_t) :: loads
    allocate(loads%force(3, n), loads%torque(3, n))
    loads%force = 0.0_wp
    loads%torque = 0.0_wp
  end function particle_loads_zero

  !> A system of the given shapes and bodies (same order). box_length: periods (0 = unbounded in
  !> that direction; absent = unbounded). contacts: closest points already known for the pairs in
  !> the order of the full pair list (1,2), (1,3), ..., (N-1,N) (e.g. from a placement), taken as
  !> current. Without a box every pair has a record; with one (periodic in some direction), only the
  !> pairs the broad phase finds within the search gap (the interaction gap; a many-body scene sets
  !> it to particle_interaction_gap(models), the DLVO cut-off; huge(): every pair). The system is not
  !> yet interacted: call particle_system_interact once before the first step.
  subroutine particle_system_create(system, shapes, bodies, models, box_length, contacts)
    type(particle_system_t), intent(out) :: system
    type(spheroid_t), intent(in) :: shapes(:)
    type(rigid_body_t), intent(in) :: bodies(:)
    type(particle_models_t), intent(in) :: models
    real(wp), intent(in), optional :: box_length(3)
    type(closest_points_t), intent(in), optional :: contacts(:)
    integer :: i, j, p, n
    if (size(shapes) /= size(bodies) .or. size(bodies) < 1) &
      call fatal('particle_system_create: one shape per body and at least one body are required')
    system%n = size(bodies)
    n = system%n
    system%shapes = shapes
    system%bodies = bodies
    system%models = models
    if (present(box_length)) then
      if (any(box_length < 0.0_wp)) call fatal('particle_system_create: box lengths must be >= 0 (0 = unbounded)')
      system%box_length = box_length
    end if
    allocate(system%bounding_radii(n))
    do i = 1, n
      system%bounding_radii(i) = bounding_radius(shapes(i))
    end do
    system%near_pairs_only = any(system%box_length > 0.0_wp)
    allocate(system%wraps(3, n))
    system%wraps = 0_i8
    call wrap_positions(system)
    if (system%near_pairs_only) then
      call find_near_pairs(system, system%models%interaction_gap)
      allocate(system%pairs(system%finder%count))
      do p = 1, system%finder%count
        system%pairs(p)%first = system%finder%first(p)
        system%pairs(p)%second = system%finder%second(p)
      end do
    else
      allocate(system%pairs(n * (n - 1) / 2))
      p = 0
      do i = 1, n - 1
        do j = i + 1, n
          p = p + 1
          system%pairs(p)%first = i
          system%pairs(p)%second = j
        end do
      end do
    end if
    if (present(contacts)) then
      if (size(contacts) /= n * (n - 1) / 2) call fatal('particle_system_create: one contact per pair is required')
      do p = 1, size(system%pairs)
        ! Position of (i, j) in the full list: the pairs of the bodies before i, then j - i.
        i = system%pairs(p)%first
        j = system%pairs(p)%second
        system%pairs(p)%contact = contacts((i - 1) * (2 * n - i) / 2 + j - i)
        system%pairs(p)%active = system%pairs(p)%contact%converged
      end do
    end if
    system%dlvo_loads = particle_loads_zero(n)
    system%collision_loads = particle_loads_zero(n)
    system%lubrication_loads = particle_loads_zero(n)
    allocate(system%impulse_added(n))
  end subroutine particle_system_create

  !> Radius (m) of a spheroid's bounding sphere: its larger semi-axis.
  pure real(wp) function bounding_radius(shape)
    type(spheroid_t), intent(in) :: shape
    bounding_radius = max(shape%a, shape%b)
  end function bounding_radius

  !> The interaction gap (m, between bounding spheres) of a many-body system: the DLVO cut-off
  !> (dlvo_cutoff_gap: both terms below dlvo_cutoff_fraction of their contact values), and at least
  !> the lubrication hand-over gap h_out (the sub-grid force acts below it); 0 without either model
  !> (collisions widen the broad phase's gap by their own detection reach every step).
  pure real(wp) function particle_interaction_gap(models)
    type(particle_models_t), intent(in) :: models
    particle_interaction_gap = 0.0_wp
    if (models%dlvo) particle_interaction_gap = dlvo_cutoff_gap(models%dlvo_model)
    if (models%lubrication) particle_interaction_gap = max(particle_interaction_gap, models%lubrication_model%outer_gap)
  end function particle_interaction_gap

  !> The added masses the bodies' contact and lubrication impulses carry from now on (one per body,
  !> body frame): those with which the coupling moves the bodies under their loads, so that an
  !> impulse and a load meet the same inertia (module rigid_body, "Impulses in a fluid").
  subroutine particle_system_set_added_inertia(system, added)
    type(particle_system_t), intent(inout) :: system
    type(added_inertia_t), intent(in) :: added(:)
    integer :: i
    if (size(added) /= system%n) call fatal('particle_system_set_added_inertia: one added inertia per body is required')
    do i = 1, system%n
      if (any(added(i)%mass < 0.0_wp) .or. any(added(i)%inertia < 0.0_wp)) &
        call fatal('particle_system_set_added_inertia: added masses and inertias must be >= 0')
    end do
    system%impulse_added = added
    system%impulses_in_fluid = .false.
    do i = 1, system%n
      if (any(added(i)%mass > 0.0_wp) .or. any(added(i)%inertia > 0.0_wp)) system%impulses_in_fluid = .true.
    end do
  end subroutine particle_system_set_added_inertia

  !> From now on the particle steps move only the bodies members (increasing indices, each at most
  !> once) and keep pair records for pairs of members only: the caller guarantees that no other
  !> body comes within the broad phase's gap of any body during those steps (module header of
  !> scene_loop, "near bodies"). The pair records of non-members are dropped at the next interaction.
  subroutine particle_system_set_members(system, members)
    type(particle_system_t), intent(inout) :: system
    integer, intent(in) :: members(:)
    integer :: k
    do k = 1, size(members)
      if (members(k) < 1 .or. members(k) > system%n) call fatal('particle_system_set_members: body index out of range')
      if (k > 1) then
        if (members(k) <= members(k - 1)) call fatal('particle_system_set_members: members must increase')
      end if
    end do
    if (allocated(system%members)) then
      if (size(system%members) /= size(members)) deallocate(system%members)
    end if
    if (.not. allocated(system%members)) allocate(system%members(size(members)))
    system%members = members
  end subroutine particle_system_set_members

  !> Every body takes the particle steps again (the default).
  subroutine particle_system_all_members(system)
    type(particle_system_t), intent(inout) :: system
    if (allocated(system%members)) deallocate(system%members)
  end subroutine particle_system_all_members

  !> One particle step of length dt (module header): Newton-Euler under external + DLVO loads, then
  !> the pair interactions of the new state. external: (3, n) loads held fixed over the call;
  !> absent = none.
  subroutine particle_system_step(system, dt, external)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    type(particle_loads_t), intent(in), optional :: external
    integer :: i
    if (allocated(system%members)) then
      call step_members(system, dt, external)
      return
    end if
    if (present(external)) then
      if (size(external%force, 2) /= system%n .or. size(external%torque, 2) /= system%n) &
        call fatal('particle_system_step: external loads are not sized for the system''s bodies')
      do i = 1, system%n
        call rigid_body_step(system%bodies(i), external%force(:, i) + system%dlvo_loads%force(:, i), &
                             external%torque(:, i) + system%dlvo_loads%torque(:, i), dt, system%models%integrator)
      end do
    else
      do i = 1, system%n
        call rigid_body_step(system%bodies(i), system%dlvo_loads%force(:, i), system%dlvo_loads%torque(:, i), dt, &
                             system%models%integrator)
      end do
    end if
    do i = 1, size(system%pairs)
      system%pairs(i)%active = .false.    ! the bodies moved: no contact is current any more
    end do
    call wrap_positions(system)
    call particle_system_interact(system, dt)
  end subroutine particle_system_step

  !> particle_system_step for the members only (the same arithmetic per body).
  subroutine step_members(system, dt, external)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    type(particle_loads_t), intent(in), optional :: external
    integer :: i, k
    if (present(external)) then
      if (size(external%force, 2) /= system%n .or. size(external%torque, 2) /= system%n) &
        call fatal('particle_system_step: external loads are not sized for the system''s bodies')
      do k = 1, size(system%members)
        i = system%members(k)
        call rigid_body_step(system%bodies(i), external%force(:, i) + system%dlvo_loads%force(:, i), &
                             external%torque(:, i) + system%dlvo_loads%torque(:, i), dt, system%models%integrator)
      end do
    else
      do k = 1, size(system%members)
        i = system%members(k)
        call rigid_body_step(system%bodies(i), system%dlvo_loads%force(:, i), system%dlvo_loads%torque(:, i), dt, &
                             system%models%integrator)
      end do
    end if
    do i = 1, size(system%pairs)
      system%pairs(i)%active = .false.
    end do
    do k = 1, size(system%members)
      call wrap_body(system, system%members(k))
    end do
    call particle_system_interact(system, dt)
  end subroutine step_members

  !> The pair interactions of the current state (steps 2-4 of the module header): with a box, the
  !> near pairs of the broad phase first (records of pairs still near kept, with their warm starts);
  !> closest points of the pairs that may interact (not recomputed where already current), collision
  !> impulses in the order of the pair list, DLVO loads. dt scales the collision detection distance
  !> (v_n dt) and the reported collision force (impulse / dt).
  subroutine particle_system_interact(system, dt)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    integer :: p
    real(wp) :: reach
    system%search_gap = system%models%interaction_gap
    if (system%models%collisions) system%search_gap = max(system%search_gap, collision_reach(system, dt))
    if (system%near_pairs_only) call refresh_pairs(system)
    ! Surfaces farther apart than this need no closest points: beyond the search gap no model acts,
    ! and beyond the DLVO range no pair is bound (module pair_outcome).
    reach = system%search_gap
    if (system%models%dlvo) reach = max(reach, dlvo_range(system%models%dlvo_model))
    do p = 1, size(system%pairs)
      call update_contact(system, system%pairs(p), reach)
    end do
    call resolve_collisions(system, dt)
    if (allocated(system%members)) then
      call zero_members(system%lubrication_loads, system%members)
    else
      system%lubrication_loads = particle_loads_zero(system%n)
    end if
    do p = 1, size(system%pairs)
      call lubricate_pair(system, system%pairs(p), dt)
    end do
    if (allocated(system%members)) then
      call zero_members(system%dlvo_loads, system%members)
    else
      system%dlvo_loads%force = 0.0_wp
      system%dlvo_loads%torque = 0.0_wp
    end if
    do p = 1, size(system%pairs)
      call dlvo_pair(system, system%pairs(p))
    end do
  end subroutine particle_system_interact

  !> The loads of the members set to zero (the others' are not touched).
  subroutine zero_members(loads, members)
    type(particle_loads_t), intent(inout) :: loads
    integer, intent(in) :: members(:)
    integer :: k
    do k = 1, size(members)
      loads%force(:, members(k)) = 0.0_wp
      loads%torque(:, members(k)) = 0.0_wp
    end do
  end subroutine zero_members

  !> The broad phase's gap (m) of a particle step dt at the current state: the interaction gap,
  !> widened by the collision reach with collisions on (particle_system_interact).
  real(wp) function particle_search_gap(system, dt)
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dt
    particle_search_gap = system%models%interaction_gap
    if (system%models%collisions) particle_search_gap = max(particle_search_gap, collision_reach(system, dt))
  end function particle_search_gap

  !> Gap (m) between bounding spheres within which a collision can be detected this step: the
  !> detection distance max(floor, factor v_n dt) at the largest approach speed two bodies can
  !> have, v_n <= s_i + s_j with s = |U| + |omega| max(a, b) (the fastest surface point).
  real(wp) function collision_reach(system, dt)
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dt
    real(wp) :: fastest
    integer :: i, k
    fastest = 0.0_wp
    do k = 1, body_count(system)
      i = body_index(system, k)
      fastest = max(fastest, norm2(system%bodies(i)%velocity) &
                             + norm2(system%bodies(i)%angular_velocity_body) * system%bounding_radii(i))
    end do
    collision_reach = max(system%models%collision_model%detection_floor, &
                          system%models%collision_model%detection_factor * 2.0_wp * fastest * dt)
  end function collision_reach

  !> The bodies the steps move: n, or the members.
  pure integer function body_count(system)
    type(particle_system_t), intent(in) :: system
    if (allocated(system%members)) then
      body_count = size(system%members)
    else
      body_count = system%n
    end if
  end function body_count

  !> The k-th body the steps move.
  pure integer function body_index(system, k)
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: k
    if (allocated(system%members)) then
      body_index = system%members(k)
    else
      body_index = k
    end if
  end function body_index

  !> The broad phase's near pairs at the current positions (system%finder), among the members if
  !> there are members (their increasing order keeps the pairs sorted by body index).
  subroutine find_near_pairs(system, gap)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: gap
    integer :: k, m
    if (.not. allocated(system%scratch_positions)) allocate(system%scratch_positions(3, system%n), &
                                                             system%scratch_radii(system%n))
    m = body_count(system)
    do k = 1, m
      system%scratch_positions(:, k) = system%bodies(body_index(system, k))%position
      system%scratch_radii(k) = system%bounding_radii(body_index(system, k))
    end do
    call broad_phase_find(system%finder, system%scratch_positions(:, 1:m), system%scratch_radii(1:m), &
                          system%box_length, gap)
    if (.not. allocated(system%members)) return
    do k = 1, system%finder%count
      system%finder%first(k) = system%members(system%finder%first(k))
      system%finder%second(k) = system%members(system%finder%second(k))
    end do
  end subroutine find_near_pairs

  !> Pair records for the near pairs of the current state, sorted by (first, second): a pair that
  !> was near before keeps its record (closest points: the warm start; flags), a new one starts
  !> from defaults, a pair no longer near is dropped. Both lists are sorted, so one merge pass.
  subroutine refresh_pairs(system)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), allocatable :: records(:)
    integer :: p, old, m
    call find_near_pairs(system, system%search_gap)
    m = system%finder%count
    if (m == size(system%pairs)) then
      if (all(system%pairs%first == system%finder%first(1:m)) .and. &
          all(system%pairs%second == system%finder%second(1:m))) return   ! the same pairs: nothing to move
    end if
    allocate(records(m))
    old = 1
    do p = 1, m
      associate (i => system%finder%first(p), j => system%finder%second(p))
        do while (old <= size(system%pairs))
          if (system%pairs(old)%first > i .or. (system%pairs(old)%first == i .and. system%pairs(old)%second >= j)) exit
          old = old + 1
        end do
        if (old <= size(system%pairs)) then
          if (system%pairs(old)%first == i .and. system%pairs(old)%second == j) records(p) = system%pairs(old)
        end if
        records(p)%first = i
        records(p)%second = j
      end associate
    end do
    call move_alloc(records, system%pairs)
  end subroutine refresh_pairs

  !> Closest points of one pair, warm-started from its last ones; inactive (and its warm start
  !> dropped) when the bounding spheres are farther apart than the broad phase's gap (the models'
  !> interaction gap, widened by the collision reach); inactive (its last closest points kept as the
  !> warm start) when a lower bound of the surface gap from the support functions exceeds reach
  !> (m): needles and disks whose bounding spheres overlap are mostly far apart.
  subroutine update_contact(system, pair, reach)
    type(particle_system_t), intent(in) :: system
    type(particle_pair_t), intent(inout) :: pair
    real(wp), intent(in) :: reach
    type(closest_points_t) :: previous   ! a copy: the result overwrites pair%contact
    type(rigid_body_t) :: first, second
    character(len=40) :: which
    if (pair%active) return
    first = system%bodies(pair%first)
    second = pair_body_image(system, pair)
    if (.not. near_pair(first%position, system%bodies(pair%second)%position, system%bounding_radii(pair%first), &
                        system%bounding_radii(pair%second), system%box_length, system%search_gap)) then
      pair%contact = closest_points_t()
      return
    end if
    if (reach < huge(1.0_wp)) then
      if (gap_lower_bound(system%shapes(pair%first), first%position, first%quaternion, system%shapes(pair%second), &
                          second%position, second%quaternion, pair%contact) > reach) return
    end if
    previous = pair%contact
    call find_closest_points(system%shapes(pair%first), first%position, first%quaternion, system%shapes(pair%second), &
                             second%position, second%quaternion, pair%contact, previous=previous)
    if (.not. pair%contact%converged .and. system%models%ghost) then
      ! Ghost bodies may lie deep inside each other, where the closest points need not exist: such
      ! a pair is not in contact (and not counted) until it has separated.
      pair%contact = closest_points_t()
      return
    end if
    if (.not. pair%contact%converged) then
      write(which, '(a,i0,a,i0)') 'bodies ', pair%first, ' and ', pair%second
      call fatal('particle system: closest points of '//trim(which)//' did not converge: '//trim(pair%contact%message))
    end if
    pair%active = .true.
  end subroutine update_contact

  !> Collision impulses of the step (docs/theory.md, "Particle system"), in waves. A wave is the set
  !> of contacts approaching (within their detection distance) when it starts; its contacts are
  !> swept in the order of the pair list (Gauss-Seidel) until none changes any more: each contact's
  !> normal impulse of the wave is projected (normal_correction) so that the contact separates at
  !> its restitution speed s = e v_n (v_n its approach speed at the start of the wave), never
  !> pulling (the wave's normal impulse >= 0) - the projected Gauss-Seidel of a contact problem with
  !> a restitution target (Moreau 1988; Catto 2005). The first impulse of a contact whose two bodies
  !> have received no impulse yet in the step is the pair's impulse of module collision (collide(),
  !> the pair's closure with its friction rule: exactly the single-pair arithmetic). Then the next
  !> wave: the contacts the last one has set approaching, until none is. So contacts hit at once
  !> are solved together (a symmetric hit has a symmetric outcome), and an impact runs down a chain
  !> contact after contact (Newton's cradle). A contact is re-tested only when one of its bodies has
  !> received an impulse since it was last tested, and counts as off its target only beyond
  !> sweep_tolerance times the largest approach speed of the step (the level the sweeps converge
  !> to). At most max_sweeps sweeps in all; one contact alone is swept once.
  subroutine resolve_collisions(system, dt)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    real(wp), parameter :: sweep_tolerance = 1.0e-10_wp
    integer(i8), allocatable :: tested(:)
    real(wp), allocatable :: separation_speed(:), normal_impulse(:)
    integer, allocatable :: members(:)
    integer(i8) :: clock
    integer :: p, q, sweeps, impulses, wave_size, cap
    real(wp) :: fastest, slowest, speed
    logical :: applied
    if (allocated(system%members)) then
      call zero_members(system%collision_loads, system%members)
    else
      system%collision_loads%force = 0.0_wp
      system%collision_loads%torque = 0.0_wp
    end if
    system%collisions_last = 0
    system%impulse_sweeps_last = 0
    system%approaching_left = 0
    do p = 1, size(system%pairs)
      system%pairs(p)%collided = .false.
    end do
    if (.not. system%models%collisions) return
    if (system%models%ghost) then
      call ghost_contacts(system, dt)
      return
    end if
    if (size(system%pairs) == 0) return
    allocate(tested(size(system%pairs)), separation_speed(size(system%pairs)), &
             normal_impulse(size(system%pairs)), members(size(system%pairs)))
    if (.not. allocated(system%touched)) allocate(system%touched(system%n))
    ! Only the bodies of the pairs are ever read or set below.
    do p = 1, size(system%pairs)
      system%touched(system%pairs(p)%first) = 0_i8
      system%touched(system%pairs(p)%second) = 0_i8
    end do
    tested = -1_i8
    clock = 0_i8
    fastest = 0.0_wp
    slowest = 0.0_wp
    sweeps = 0
    cap = system%models%collision_model%max_sweeps
    waves: do
      ! The wave: the contacts approaching now (only those whose bodies moved since their last test).
      wave_size = 0
      do p = 1, size(system%pairs)
        associate (pair => system%pairs(p))
          if (max(system%touched(pair%first), system%touched(pair%second)) <= tested(p)) cycle
          tested(p) = clock
          if (.not. pair%active) cycle
          if (.not. pair_approaching(system, pair, dt, slowest, fastest)) cycle
          wave_size = wave_size + 1
          members(wave_size) = p
          speed = normal_speed_at(system%bodies(pair%first), pair_body_image(system, pair), pair%contact%point1, &
                                  pair%contact%point2, pair%contact%normal)
          separation_speed(p) = system%models%collision_model%restitution * max(speed, 0.0_wp)
          normal_impulse(p) = 0.0_wp
          tested(p) = -1_i8            ! swept at least once in the wave
        end associate
      end do
      if (wave_size == 0) exit waves
      do
        if (sweeps >= cap) exit waves
        impulses = 0
        do q = 1, wave_size
          p = members(q)
          associate (pair => system%pairs(p))
            if (max(system%touched(pair%first), system%touched(pair%second)) <= tested(p)) cycle
            if (system%touched(pair%first) == 0_i8 .and. system%touched(pair%second) == 0_i8) then
              call collide_pair(system, pair, dt, slowest, applied, fastest)
              if (applied) then
                separation_speed(p) = pair%collision%restitution_used * pair%collision%normal_velocity_before
                normal_impulse(p) = dot_product(pair%collision%impulse, pair%collision%normal)
              end if
            else
              call correct_pair(system, pair, dt, slowest, separation_speed(p), normal_impulse(p), applied)
            end if
            if (applied) then
              clock = clock + 1_i8
              system%touched(pair%first) = clock
              system%touched(pair%second) = clock
              impulses = impulses + 1
            end if
            tested(p) = clock
          end associate
        end do
        if (impulses == 0) exit
        sweeps = sweeps + 1
        slowest = sweep_tolerance * fastest
      end do
    end do waves
    system%impulse_sweeps_last = sweeps
    system%impulse_sweeps_most = max(system%impulse_sweeps_most, sweeps)
    if (sweeps < cap) return
    ! The cap was reached: count the contacts still approaching.
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p))
        if (.not. pair%active) cycle
        if (pair_approaching(system, pair, dt, slowest)) system%approaching_left = system%approaching_left + 1
      end associate
    end do
    if (system%approaching_left == 0) return
    system%sweep_caps_total = system%sweep_caps_total + 1_i8
    ! Logged the 1st, 10th, 100th, ... time (a long run that keeps hitting the cap says so, not every step).
    if (system%sweep_caps_total == 10_i8**int(log10(real(system%sweep_caps_total, wp)))) &
      call log_line('particle system: the impulse sweeps reached &collision max_impulse_sweeps = '// &
                    int_text(cap)//' with '//int_text(system%approaching_left)//' contact(s) still approaching ('// &
                    int_text(system%sweep_caps_total)//' step(s) so far)')
  end subroutine resolve_collisions

  !> Ghost collisions (models%ghost): every pair whose surfaces meet within the next step at the
  !> current relative velocity, 0 <= gap < v_n dt (v_n the approach speed of the closest points), is
  !> a collision of the kinematic collision rate (Wang, Wexler & Zhou 2000): counted and recorded
  !> (collided, with v_n before and after), no impulse. A pair moving at constant velocities is
  !> counted once per encounter: the step after, its gap is negative (overlap) until it separates.
  subroutine ghost_contacts(system, dt)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    real(wp) :: speed
    integer :: p
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p))
        if (.not. pair%active) cycle
        if (.not. (pair%contact%gap >= 0.0_wp)) cycle
        speed = approach_speed(system%bodies(pair%first), pair_body_image(system, pair), pair%contact%point1, &
                               pair%contact%point2, pair%contact%normal)
        if (.not. (pair%contact%gap < speed * dt)) cycle
        pair%collided = .true.
        pair%collision = collision_result_t(contact_point=0.5_wp * (pair%contact%point1 + pair%contact%point2), &
            normal=pair%contact%normal, normal_velocity_before=speed, normal_velocity_after=speed)
        system%collisions_last = system%collisions_last + 1
        system%collisions_total = system%collisions_total + 1_i8
      end associate
    end do
  end subroutine ghost_contacts

  !> One projected Gauss-Seidel update of a contact of the wave (resolve_collisions): applied when
  !> the contact's normal speed is off its target -separation_speed by more than slowest and the
  !> wave's normal impulse may move that way (it stays >= 0).
  subroutine correct_pair(system, pair, dt, slowest, separation_speed, normal_impulse, applied)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), intent(inout) :: pair
    real(wp), intent(in) :: dt, slowest, separation_speed
    real(wp), intent(inout) :: normal_impulse
    logical, intent(out) :: applied
    type(rigid_body_t) :: second
    real(wp) :: speed, impulse(3), before
    applied = .false.
    second = pair_body_image(system, pair)
    speed = normal_speed_at(system%bodies(pair%first), second, pair%contact%point1, pair%contact%point2, &
                            pair%contact%normal)
    if (.not. (speed + separation_speed > slowest .or. &
               (speed + separation_speed < -slowest .and. normal_impulse > 0.0_wp))) return
    before = normal_impulse
    if (system%impulses_in_fluid) then
      call normal_correction(system%bodies(pair%first), second, pair%contact%point1, pair%contact%point2, &
                             pair%contact%normal, separation_speed, normal_impulse, impulse, &
                             system%impulse_added(pair%first), system%impulse_added(pair%second))
    else
      call normal_correction(system%bodies(pair%first), second, pair%contact%point1, pair%contact%point2, &
                             pair%contact%normal, separation_speed, normal_impulse, impulse)
    end if
    if (.not. (abs(normal_impulse - before) > 0.0_wp)) return
    system%bodies(pair%second)%velocity = second%velocity
    system%bodies(pair%second)%angular_velocity_body = second%angular_velocity_body
    applied = .true.
    if (.not. pair%collided) then
      pair%collision = collision_result_t()
      pair%collision%contact_point = 0.5_wp * (pair%contact%point1 + pair%contact%point2)
      pair%collision%normal = pair%contact%normal / norm2(pair%contact%normal)
      pair%collision%normal_velocity_before = speed
      pair%collision%regime = regime_frictionless
      pair%collided = .true.
      system%collisions_last = system%collisions_last + 1
      system%collisions_total = system%collisions_total + 1_i8
    end if
    pair%collision%impulse = pair%collision%impulse + impulse
    pair%collision%normal_velocity_after = normal_speed_at(system%bodies(pair%first), second, pair%contact%point1, &
                                                           pair%contact%point2, pair%contact%normal)
    if (pair%collision%normal_velocity_before > 0.0_wp) pair%collision%restitution_used = &
        max(0.0_wp, -pair%collision%normal_velocity_after / pair%collision%normal_velocity_before)
    call add_impulse_loads(system, pair, impulse, second%position, dt)
  end subroutine correct_pair

  !> The collision loads of the outputs (impulse / dt, paper Eq. 17) of an impulse on the pair's
  !> second body (its image at second_position) and the opposite one on the first, at x_c.
  subroutine add_impulse_loads(system, pair, impulse, second_position, dt)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), intent(in) :: pair
    real(wp), intent(in) :: impulse(3), second_position(3), dt
    real(wp) :: force(3), point(3)
    force = impulse / dt
    point = pair%collision%contact_point
    associate (loads => system%collision_loads)
      loads%force(:, pair%first) = loads%force(:, pair%first) - force
      loads%force(:, pair%second) = loads%force(:, pair%second) + force
      loads%torque(:, pair%first) = loads%torque(:, pair%first) + cross(point - system%bodies(pair%first)%position, -force)
      loads%torque(:, pair%second) = loads%torque(:, pair%second) + cross(point - second_position, force)
    end associate
  end subroutine add_impulse_loads

  !> The collision test of one pair on the current velocities: approaching faster than slowest and
  !> within the detection distance (module collision); fastest: raised to the pair's approach speed.
  logical function pair_approaching(system, pair, dt, slowest, fastest)
    type(particle_system_t), intent(in) :: system
    type(particle_pair_t), intent(in) :: pair
    real(wp), intent(in) :: dt, slowest
    real(wp), intent(inout), optional :: fastest
    real(wp) :: speed
    type(rigid_body_t) :: second
    second = pair_body_image(system, pair)
    if (slowest > 0.0_wp) then
      speed = approach_speed(system%bodies(pair%first), second, pair%contact%point1, pair%contact%point2, &
                             pair%contact%normal)
      if (present(fastest)) fastest = max(fastest, speed)
      pair_approaching = speed > slowest .and. pair%contact%gap < detection_distance(system%models%collision_model, speed, dt)
    else
      pair_approaching = collision_detected(system%models%collision_model, system%bodies(pair%first), second, &
                                            pair%contact, dt)
      if (present(fastest) .and. pair_approaching) fastest = max(fastest, approach_speed(system%bodies(pair%first), &
          second, pair%contact%point1, pair%contact%point2, pair%contact%normal))
    end if
  end function pair_approaching

  !> Collision test and impulse of one pair on the current velocities (the bodies' own copies are
  !> updated at once, so the next pair in the sweep sees them); slowest: the smallest approach speed
  !> that counts (0: any, the single-pass test); fastest: the largest approach speed met so far.
  subroutine collide_pair(system, pair, dt, slowest, applied, fastest)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), intent(inout) :: pair
    real(wp), intent(in) :: dt, slowest
    logical, intent(out) :: applied
    real(wp), intent(inout) :: fastest
    type(rigid_body_t) :: second
    real(wp) :: force(3)
    applied = .false.
    if (.not. pair%active) return
    if (.not. pair_approaching(system, pair, dt, slowest, fastest)) return
    second = pair_body_image(system, pair)
    if (system%impulses_in_fluid) then
      call collide(system%models%collision_model, system%bodies(pair%first), second, pair%contact, pair%collision, &
                   system%impulse_added(pair%first), system%impulse_added(pair%second))
    else
      call collide(system%models%collision_model, system%bodies(pair%first), second, pair%contact, pair%collision)
    end if
    system%bodies(pair%second)%velocity = second%velocity
    system%bodies(pair%second)%angular_velocity_body = second%angular_velocity_body
    pair%collided = .true.
    applied = .true.
    system%collisions_last = system%collisions_last + 1
    system%collisions_total = system%collisions_total + 1_i8
    ! The collision force of the outputs: the impulse over dt (paper, Eq. 17) at the contact point.
    force = pair%collision%impulse / dt
    associate (loads => system%collision_loads)
      loads%force(:, pair%first) = loads%force(:, pair%first) - force
      loads%force(:, pair%second) = loads%force(:, pair%second) + force
      loads%torque(:, pair%first) = loads%torque(:, pair%first) &
          + cross(pair%collision%contact_point - system%bodies(pair%first)%position, -force)
      loads%torque(:, pair%second) = loads%torque(:, pair%second) &
          + cross(pair%collision%contact_point - second%position, force)
    end associate
  end subroutine collide_pair

  !> Lubrication impulse of one pair at its closest points (module lubrication), applied at once.
  subroutine lubricate_pair(system, pair, dt)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), intent(inout) :: pair
    real(wp), intent(in) :: dt
    type(rigid_body_t) :: second
    pair%lubrication = lubrication_result_t()
    if (.not. (system%models%lubrication .and. pair%active)) return
    second = pair_body_image(system, pair)
    if (system%impulses_in_fluid) then
      call lubricate(system%models%lubrication_model, system%shapes(pair%first), system%bodies(pair%first), &
                     system%shapes(pair%second), second, pair%contact, dt, pair%lubrication, &
                     system%impulse_added(pair%first), system%impulse_added(pair%second))
    else
      call lubricate(system%models%lubrication_model, system%shapes(pair%first), system%bodies(pair%first), &
                     system%shapes(pair%second), second, pair%contact, dt, pair%lubrication)
    end if
    system%bodies(pair%second)%velocity = second%velocity
    system%bodies(pair%second)%angular_velocity_body = second%angular_velocity_body
    associate (loads => system%lubrication_loads)
      loads%force(:, pair%first) = loads%force(:, pair%first) - pair%lubrication%force
      loads%torque(:, pair%first) = loads%torque(:, pair%first) + pair%lubrication%torque1
      loads%force(:, pair%second) = loads%force(:, pair%second) + pair%lubrication%force
      loads%torque(:, pair%second) = loads%torque(:, pair%second) + pair%lubrication%torque2
    end associate
  end subroutine lubricate_pair

  !> DLVO loads of one pair at its closest points, added to both bodies.
  subroutine dlvo_pair(system, pair)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), intent(inout) :: pair
    type(rigid_body_t) :: second
    pair%dlvo = dlvo_evaluation_t()
    if (.not. (system%models%dlvo .and. pair%active)) return
    ! Beyond the interaction gap both terms are below their cut-off fraction (particle_interaction_gap):
    ! no force. The pair scenes (gap huge) never cut the force off.
    if (pair%contact%gap > system%models%interaction_gap) return
    second = pair_body_image(system, pair)
    call dlvo_evaluate(system%models%dlvo_model, system%shapes(pair%first), system%bodies(pair%first), &
                       system%shapes(pair%second), second, pair%contact, pair%dlvo)
    associate (loads => system%dlvo_loads)
      loads%force(:, pair%first) = loads%force(:, pair%first) + pair%dlvo%force1
      loads%torque(:, pair%first) = loads%torque(:, pair%first) + pair%dlvo%torque1
      loads%force(:, pair%second) = loads%force(:, pair%second) + pair%dlvo%force2
      loads%torque(:, pair%second) = loads%torque(:, pair%second) + pair%dlvo%torque2
    end associate
  end subroutine dlvo_pair

  !> Shift (m) that takes the second body of a pair to its minimum image next to the first; zero
  !> without a box (so the unbounded pair scenes do exactly the arithmetic they always did).
  pure function pair_image(system, pair) result(shift)
    type(particle_system_t), intent(in) :: system
    type(particle_pair_t), intent(in) :: pair
    real(wp) :: shift(3)
    shift = image_shift(system%bodies(pair%second)%position - system%bodies(pair%first)%position, system%box_length)
  end function pair_image

  !> A copy of the pair's second body placed at its minimum image next to the first.
  pure function pair_body_image(system, pair) result(body)
    type(particle_system_t), intent(in) :: system
    type(particle_pair_t), intent(in) :: pair
    type(rigid_body_t) :: body
    body = system%bodies(pair%second)
    body%position = body%position + pair_image(system, pair)
  end function pair_body_image

  !> Continuous (unwrapped) position of body i: the wrapped position plus the box crossings.
  pure function unwrapped_position(system, i) result(position)
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: i
    real(wp) :: position(3)
    position = system%bodies(i)%position + real(system%wraps(:, i), wp) * system%box_length
  end function unwrapped_position

  !> Kinetic energy of all bodies (J).
  pure real(wp) function particle_system_energy(system)
    type(particle_system_t), intent(in) :: system
    integer :: i
    particle_system_energy = 0.0_wp
    do i = 1, system%n
      particle_system_energy = particle_system_energy + kinetic_energy(system%bodies(i))
    end do
  end function particle_system_energy

  !> Wrap positions into [0, L) in every periodic direction, counting the crossings.
  subroutine wrap_positions(system)
    type(particle_system_t), intent(inout) :: system
    integer :: i
    do i = 1, system%n
      call wrap_body(system, i)
    end do
  end subroutine wrap_positions

  !> Wrap body i's position into [0, L) in every periodic direction, counting the crossings.
  subroutine wrap_body(system, i)
    type(particle_system_t), intent(inout) :: system
    integer, intent(in) :: i
    integer :: k
    integer(i8) :: crossings
    do k = 1, 3
      if (system%box_length(k) <= 0.0_wp) cycle
      crossings = floor(system%bodies(i)%position(k) / system%box_length(k), i8)
      if (crossings == 0_i8) cycle
      system%bodies(i)%position(k) = system%bodies(i)%position(k) - real(crossings, wp) * system%box_length(k)
      ! Round-off can leave x = L after the subtraction (x just below 0): fold it to 0.
      if (system%bodies(i)%position(k) >= system%box_length(k)) then
        system%bodies(i)%position(k) = system%bodies(i)%position(k) - system%box_length(k)
        crossings = crossings + 1_i8
      end if
      system%wraps(k, i) = system%wraps(k, i) + crossings
    end do
  end subroutine wrap_body

end module particle_system
