!> The state of a particle system as plain arrays, for a checkpoint group written by io/ (which
!> knows no particles) and read back for a restart that continues bit for bit (docs/theory.md,
!> "Particle system"). Between steps a system is current (module particle_system), so the state is
!> everything a step reads: the bodies, the box crossings, each pair's closest points (the next warm
!> start), its DLVO evaluation and flags, the per-body loads and the collision counters. Shapes,
!> models and the box are the scene's set-up, rebuilt from the deck: restore into a system created
!> from them, and do not call particle_system_interact again.
!> The pair arrays follow the system's pair records: every pair i < j in the order (1,2), (1,3), ...
!> for a system without a box, the near pairs with a box; pair_bodies (2, pairs) names them, and a
!> state without pair_bodies (a checkpoint of a pair scene) means the full list.
module particle_system_state
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use particle_system, only: particle_system_t
  implicit none
  private
  public :: particle_system_state_t, particle_system_save, particle_system_restore

  !> Rows of each array (the first dimension); the second is the body or pair index.
  integer, parameter, public :: body_rows = 13, contact_rows = 16, dlvo_rows = 17, load_rows = 12, flag_rows = 3

  type :: particle_system_state_t
    !> (13, n): position(3), velocity(3), quaternion(4), angular_velocity_body(3)
    real(wp), allocatable :: bodies(:,:)
    integer(i8), allocatable :: wraps(:,:)       !< (3, n): box crossings
    !> (16, pairs): gap, point1(3), point2(3), normal(3), theta1, phi1, theta2, phi2, residual, distance_bound
    real(wp), allocatable :: contacts(:,:)
    !> (17, pairs): chi_eta, force, vdw_force, edl_force, energy, force1(3), torque1(3), force2(3), torque2(3)
    real(wp), allocatable :: dlvo(:,:)
    integer, allocatable :: flags(:,:)           !< (3, pairs): active, contact converged, collided (0 | 1)
    integer, allocatable :: pair_bodies(:,:)     !< (2, pairs): first, second (absent: the full list i < j)
    !> (12, n): DLVO force(3), torque(3), collision force(3), torque(3)
    real(wp), allocatable :: loads(:,:)
    integer(i8) :: counters(2) = 0_i8            !< collisions_total, collisions_last
  end type particle_system_state_t

contains

  subroutine particle_system_save(system, state)
    type(particle_system_t), intent(in) :: system
    type(particle_system_state_t), intent(out) :: state
    integer :: i, p
    allocate(state%bodies(body_rows, system%n), state%loads(load_rows, system%n))
    allocate(state%contacts(contact_rows, size(system%pairs)), state%dlvo(dlvo_rows, size(system%pairs)), &
             state%flags(flag_rows, size(system%pairs)))
    state%wraps = system%wraps
    allocate(state%pair_bodies(2, size(system%pairs)))
    state%pair_bodies(1, :) = system%pairs%first
    state%pair_bodies(2, :) = system%pairs%second
    do i = 1, system%n
      associate (body => system%bodies(i))
        state%bodies(:, i) = [body%position, body%velocity, body%quaternion, body%angular_velocity_body]
      end associate
      state%loads(:, i) = [system%dlvo_loads%force(:, i), system%dlvo_loads%torque(:, i), &
                           system%collision_loads%force(:, i), system%collision_loads%torque(:, i)]
    end do
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p), contact => system%pairs(p)%contact, dlvo => system%pairs(p)%dlvo)
        state%contacts(:, p) = [contact%gap, contact%point1, contact%point2, contact%normal, contact%theta1, &
                                contact%phi1, contact%theta2, contact%phi2, contact%residual, contact%distance_bound]
        state%dlvo(:, p) = [dlvo%chi_eta, dlvo%force, dlvo%vdw_force, dlvo%edl_force, dlvo%energy, dlvo%force1, &
                            dlvo%torque1, dlvo%force2, dlvo%torque2]
        state%flags(:, p) = [merge(1, 0, pair%active), merge(1, 0, contact%converged), merge(1, 0, pair%collided)]
      end associate
    end do
    state%counters = [system%collisions_total, int(system%collisions_last, i8)]
  end subroutine particle_system_save

  !> Put a saved state into a system created from the same shapes, models and box.
  subroutine particle_system_restore(system, state)
    type(particle_system_t), intent(inout) :: system
    type(particle_system_state_t), intent(in) :: state
    integer :: i, p
    character(len=120) :: text
    if (.not. (allocated(state%bodies) .and. allocated(state%wraps) .and. allocated(state%contacts) .and. &
               allocated(state%dlvo) .and. allocated(state%flags) .and. allocated(state%loads))) &
      call fatal('particle_system_restore: the saved particle state is incomplete')
    if (allocated(state%pair_bodies)) then
      call restore_pair_list(system, state%pair_bodies)
    else if (size(system%pairs) /= system%n * (system%n - 1) / 2) then
      call restore_pair_list(system, full_pair_list(system%n))
    end if
    if (any(shape(state%bodies) /= [body_rows, system%n]) .or. any(shape(state%wraps) /= [3, system%n]) .or. &
        any(shape(state%loads) /= [load_rows, system%n]) .or. &
        any(shape(state%contacts) /= [contact_rows, size(system%pairs)]) .or. &
        any(shape(state%dlvo) /= [dlvo_rows, size(system%pairs)]) .or. &
        any(shape(state%flags) /= [flag_rows, size(system%pairs)])) then
      write(text, '(a,i0,a,i0,a)') ' (the system has ', system%n, ' bodies, the saved state ', size(state%bodies, 2), ')'
      call fatal('particle_system_restore: the saved particle state does not fit this system'//trim(text))
    end if
    system%wraps = state%wraps
    do i = 1, system%n
      associate (body => system%bodies(i), row => state%bodies(:, i))
        body%position = row(1:3)
        body%velocity = row(4:6)
        body%quaternion = row(7:10)
        body%angular_velocity_body = row(11:13)
      end associate
      system%dlvo_loads%force(:, i) = state%loads(1:3, i)
      system%dlvo_loads%torque(:, i) = state%loads(4:6, i)
      system%collision_loads%force(:, i) = state%loads(7:9, i)
      system%collision_loads%torque(:, i) = state%loads(10:12, i)
    end do
    do p = 1, size(system%pairs)
      associate (pair => system%pairs(p), row => state%contacts(:, p), saved => state%dlvo(:, p))
        pair%contact%gap = row(1)
        pair%contact%point1 = row(2:4)
        pair%contact%point2 = row(5:7)
        pair%contact%normal = row(8:10)
        pair%contact%theta1 = row(11)
        pair%contact%phi1 = row(12)
        pair%contact%theta2 = row(13)
        pair%contact%phi2 = row(14)
        pair%contact%residual = row(15)
        pair%contact%distance_bound = row(16)
        pair%contact%converged = state%flags(2, p) == 1
        pair%contact%message = ''
        pair%active = state%flags(1, p) == 1
        pair%collided = state%flags(3, p) == 1
        pair%dlvo%chi_eta = saved(1)
        pair%dlvo%force = saved(2)
        pair%dlvo%vdw_force = saved(3)
        pair%dlvo%edl_force = saved(4)
        pair%dlvo%energy = saved(5)
        pair%dlvo%force1 = saved(6:8)
        pair%dlvo%torque1 = saved(9:11)
        pair%dlvo%force2 = saved(12:14)
        pair%dlvo%torque2 = saved(15:17)
      end associate
    end do
    system%collisions_total = state%counters(1)
    system%collisions_last = int(state%counters(2))
  end subroutine particle_system_restore

  !> Every pair i < j of n bodies, (2, n (n - 1) / 2), in the order (1,2), (1,3), ..., (n-1,n).
  pure function full_pair_list(n) result(list)
    integer, intent(in) :: n
    integer :: list(2, n * (n - 1) / 2)
    integer :: i, j, p
    p = 0
    do i = 1, n - 1
      do j = i + 1, n
        p = p + 1
        list(:, p) = [i, j]
      end do
    end do
  end function full_pair_list

  !> Pair records for the saved pairs (first, second), which must be pairs i < j of this system's
  !> bodies in increasing order (the order of the sweep).
  subroutine restore_pair_list(system, pair_bodies)
    type(particle_system_t), intent(inout) :: system
    integer, intent(in) :: pair_bodies(:,:)
    integer :: p
    logical :: valid
    valid = size(pair_bodies, 1) == 2
    if (valid .and. size(pair_bodies, 2) > 0) valid = all(pair_bodies(1, :) >= 1) .and. &
        all(pair_bodies(1, :) < pair_bodies(2, :)) .and. all(pair_bodies(2, :) <= system%n)
    do p = 2, size(pair_bodies, 2)
      if (.not. valid) exit
      valid = pair_bodies(1, p - 1) < pair_bodies(1, p) .or. &
              (pair_bodies(1, p - 1) == pair_bodies(1, p) .and. pair_bodies(2, p - 1) < pair_bodies(2, p))
    end do
    if (.not. valid) call fatal('particle_system_restore: the saved pairs are not pairs i < j of the system''s '// &
                                'bodies in increasing order')
    if (allocated(system%pairs)) deallocate(system%pairs)
    allocate(system%pairs(size(pair_bodies, 2)))
    system%pairs%first = pair_bodies(1, :)
    system%pairs%second = pair_bodies(2, :)
  end subroutine restore_pair_list
end module particle_system_state
