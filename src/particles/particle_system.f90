!> N rigid spheroids, the pairs among them and their one particle step (docs/theory.md, "Particle
!> system"; docs/design.md, data flow step 6).
!>
!> The system owns the bodies (shape, mass, inertia, state), the pairs i < j (closest points kept
!> as the warm start of the next step, the DLVO evaluation, this step's collision) and the loads the
!> pair interactions put on each body. One step of length dt:
!>   1. Newton-Euler update of every body under the external loads of the call (frozen over the
!>      call: Stokes resistance in the pair scenes, resolved hydrodynamic loads later) plus the
!>      DLVO loads of the current state; positions wrapped into the periodic box, if any;
!>   2. closest points of every pair that may interact (periodic minimum image), warm-started;
!>   3. collision test and impulse, pair by pair in the order of the pair list (below);
!>   4. DLVO at the closest points, summed per body for the next Newton-Euler update.
!> Steps 2-4 are particle_system_interact, which also prepares a new system (or one read back from
!> a checkpoint), so that between calls the system is always CURRENT: contacts, collision loads and
!> DLVO loads belong to the positions and velocities it holds, which is the state an output, an
!> outcome test, a checkpoint or the next fluid step sees. The per-pair work is recomputed every
!> particle step; nothing pair-related is ever frozen.
!>
!> Order of simultaneous impulses: the pairs are visited once per step in the order of the pair list,
!> (1,2), (1,3), ..., (1,N), (2,3), ..., (N-1,N); each pair is tested with the velocities left by
!> the impulses before it and its impulse applied at once (one sequential, Gauss-Seidel sweep).
!> For three spheres in a line, 1 -> 2 -> 3, touching at the same step, the 1-2 impulse comes first
!> and then the 2-3 test sees the velocity body 2 has just received: the Newton's cradle result.
!> Every impulse conserves linear and angular momentum and, with e = 1 head-on, energy (to round-off).
!> Pairs whose bounding spheres are farther apart than models%interaction_gap skip steps 2-4.
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
  use closest_points, only: closest_points_t, find_closest_points
  use dlvo, only: dlvo_model_t, dlvo_evaluation_t, dlvo_evaluate
  use collision, only: collision_model_t, collision_result_t, collision_detected, collide
  use lubrication, only: lubrication_model_t, lubrication_result_t, lubricate
  use vector_algebra, only: cross
  use periodic_box, only: image_shift
  implicit none
  private
  public :: particle_models_t, particle_pair_t, particle_loads_t, particle_system_t, particle_system_create, &
            particle_system_interact, particle_system_step, particle_loads_zero, &
            unwrapped_position, pair_image, pair_body_image, particle_system_energy, particle_system_set_added_inertia

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
    type(particle_pair_t), allocatable :: pairs(:)       !< (n (n - 1) / 2), in the order of the sweep
    type(particle_loads_t) :: dlvo_loads                 !< summed over pairs, current state
    type(particle_loads_t) :: collision_loads            !< impulse / dt of the last interaction (outputs)
    type(particle_loads_t) :: lubrication_loads          !< lubrication impulse / dt of the last interaction
    integer :: collisions_last = 0                       !< impulses in the last interaction
    integer(i8) :: collisions_total = 0_i8               !< impulses since creation
    !> (n) the fluid's added masses that collision and lubrication impulses move with each body
    !> (module rigid_body, added_inertia_t): zero (bodies alone) unless a coupling that takes the
    !> added mass implicitly sets them (particle_system_set_added_inertia)
    type(added_inertia_t), allocatable :: impulse_added(:)
    logical :: impulses_in_fluid = .false.               !< some impulse_added is non-zero
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
  !> the order of the pair list (e.g. from a placement), taken as current. The system is not yet
  !> interacted: call particle_system_interact once before the first step.
  subroutine particle_system_create(system, shapes, bodies, models, box_length, contacts)
    type(particle_system_t), intent(out) :: system
    type(spheroid_t), intent(in) :: shapes(:)
    type(rigid_body_t), intent(in) :: bodies(:)
    type(particle_models_t), intent(in) :: models
    real(wp), intent(in), optional :: box_length(3)
    type(closest_points_t), intent(in), optional :: contacts(:)
    integer :: i, j, p
    if (size(shapes) /= size(bodies) .or. size(bodies) < 1) &
      call fatal('particle_system_create: one shape per body and at least one body are required')
    system%n = size(bodies)
    system%shapes = shapes
    system%bodies = bodies
    system%models = models
    if (present(box_length)) then
      if (any(box_length < 0.0_wp)) call fatal('particle_system_create: box lengths must be >= 0 (0 = unbounded)')
      system%box_length = box_length
    end if
    allocate(system%wraps(3, system%n))
    system%wraps = 0_i8
    call wrap_positions(system)
    allocate(system%pairs(system%n * (system%n - 1) / 2))
    p = 0
    do i = 1, system%n - 1
      do j = i + 1, system%n
        p = p + 1
        system%pairs(p)%first = i
        system%pairs(p)%second = j
      end do
    end do
    if (present(contacts)) then
      if (size(contacts) /= size(system%pairs)) call fatal('particle_system_create: one contact per pair is required')
      do p = 1, size(system%pairs)
        system%pairs(p)%contact = contacts(p)
        system%pairs(p)%active = contacts(p)%converged
      end do
    end if
    system%dlvo_loads = particle_loads_zero(system%n)
    system%collision_loads = particle_loads_zero(system%n)
    system%lubrication_loads = particle_loads_zero(system%n)
    allocate(system%impulse_added(system%n))
  end subroutine particle_system_create

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

  !> One particle step of length dt (module header): Newton-Euler under external + DLVO loads, then
  !> the pair interactions of the new state. external: (3, n) loads held fixed over the call;
  !> absent = none.
  subroutine particle_system_step(system, dt, external)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    type(particle_loads_t), intent(in), optional :: external
    integer :: i
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

  !> The pair interactions of the current state (steps 2-4 of the module header): closest points of
  !> the pairs that may interact (not recomputed where already current), collision impulses in the
  !> order of the pair list, DLVO loads. dt scales the collision detection distance (v_n dt) and
  !> the reported collision force (impulse / dt).
  subroutine particle_system_interact(system, dt)
    type(particle_system_t), intent(inout) :: system
    real(wp), intent(in) :: dt
    integer :: p
    do p = 1, size(system%pairs)
      call update_contact(system, system%pairs(p))
    end do
    system%collision_loads%force = 0.0_wp
    system%collision_loads%torque = 0.0_wp
    system%collisions_last = 0
    do p = 1, size(system%pairs)
      call collide_pair(system, system%pairs(p), dt)
    end do
    system%lubrication_loads = particle_loads_zero(system%n)
    do p = 1, size(system%pairs)
      call lubricate_pair(system, system%pairs(p), dt)
    end do
    system%dlvo_loads%force = 0.0_wp
    system%dlvo_loads%torque = 0.0_wp
    do p = 1, size(system%pairs)
      call dlvo_pair(system, system%pairs(p))
    end do
  end subroutine particle_system_interact

  !> Closest points of one pair, warm-started from its last ones; inactive (and its warm start
  !> dropped) when the bounding spheres are farther apart than the models' interaction gap.
  subroutine update_contact(system, pair)
    type(particle_system_t), intent(in) :: system
    type(particle_pair_t), intent(inout) :: pair
    type(closest_points_t) :: previous   ! a copy: the result overwrites pair%contact
    type(rigid_body_t) :: first, second
    real(wp) :: reach
    character(len=40) :: which
    if (pair%active) return
    first = system%bodies(pair%first)
    second = pair_body_image(system, pair)
    reach = max(system%shapes(pair%first)%a, system%shapes(pair%first)%b) &
            + max(system%shapes(pair%second)%a, system%shapes(pair%second)%b)
    if (norm2(second%position - first%position) - reach > system%models%interaction_gap) then
      pair%contact = closest_points_t()
      return
    end if
    previous = pair%contact
    call find_closest_points(system%shapes(pair%first), first%position, first%quaternion, system%shapes(pair%second), &
                             second%position, second%quaternion, pair%contact, previous=previous)
    if (.not. pair%contact%converged) then
      write(which, '(a,i0,a,i0)') 'bodies ', pair%first, ' and ', pair%second
      call fatal('particle system: closest points of '//trim(which)//' did not converge: '//trim(pair%contact%message))
    end if
    pair%active = .true.
  end subroutine update_contact

  !> Collision test and impulse of one pair on the current velocities (the bodies' own copies are
  !> updated at once, so the next pair in the sweep sees them).
  subroutine collide_pair(system, pair, dt)
    type(particle_system_t), intent(inout) :: system
    type(particle_pair_t), intent(inout) :: pair
    real(wp), intent(in) :: dt
    type(rigid_body_t) :: second
    real(wp) :: force(3)
    pair%collided = .false.
    if (.not. (system%models%collisions .and. pair%active)) return
    second = pair_body_image(system, pair)
    if (.not. collision_detected(system%models%collision_model, system%bodies(pair%first), second, pair%contact, dt)) &
      return
    if (system%impulses_in_fluid) then
      call collide(system%models%collision_model, system%bodies(pair%first), second, pair%contact, pair%collision, &
                   system%impulse_added(pair%first), system%impulse_added(pair%second))
    else
      call collide(system%models%collision_model, system%bodies(pair%first), second, pair%contact, pair%collision)
    end if
    system%bodies(pair%second)%velocity = second%velocity
    system%bodies(pair%second)%angular_velocity_body = second%angular_velocity_body
    pair%collided = .true.
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
    integer :: i, k
    integer(i8) :: crossings
    do i = 1, system%n
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
    end do
  end subroutine wrap_positions

end module particle_system
