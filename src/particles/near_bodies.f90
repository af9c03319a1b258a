!> The bodies of a suspension that take the particle sub-steps of a fluid step (&scene
!> substep_bodies = 'near'; docs/theory.md, "Near-pair sub-steps"): those of the pairs that may come
!> within the broad phase's gap g0 (the interaction gap, widened by the collision reach of a sub-step)
!> during the fluid step dt. The others have no pair force over the step and take it in one update.
!>
!> A pair (i, j) may come near when its bounding spheres' gap at the start is within
!>   g0 + safety dt s_ij,   s_ij = max(|U_j - U_i|, |u_j^n - u_i^n|, |u_j^n+1 - u_i^n+1|),
!> the largest relative speed of the two bodies or of the fluid at their centres at either end of the
!> step (a body with a Stokes time short against dt moves with the fluid; its relative velocity
!> relaxes from its own towards the fluid's), with the margin safety = 2 for the slip and the
!> change of the fluid along the paths. Candidates come from one broad phase (module broad_phase)
!> with the gap g0 + safety dt 2 max_i s_i, s_i = max(|U_i|, |u_i^n|, |u_i^n+1|), an upper bound of
!> every s_ij. The bound is checked after the step: a pair within g0 at the start of the next step
!> with a body that took the one-step update is a miss (counted; zero in every run measured).
!> On several ranks each searches the pairs whose first body is its by stride (shared_work) and the
!> members, pairs and misses are combined over the ranks: the same as one rank's search.
module near_bodies
  use agglo_kinds, only: wp, i8
  use shared_work, only: rank_stride, any_of_ranks, sum_of_ranks
  use broad_phase, only: broad_phase_t, broad_phase_find
  use particle_system, only: particle_system_t
  use periodic_box, only: minimum_image
  implicit none
  private
  public :: near_bodies_t, near_bodies_find

  !> The margin on the relative speed over the step (module header).
  real(wp), parameter :: safety = 2.0_wp

  type :: near_bodies_t
    integer :: count = 0                        !< members(1:count): the bodies of the sub-steps, increasing
    integer, allocatable :: members(:)          !< (n)
    integer, allocatable :: single(:)           !< (n): single(1:n - count), the others, increasing
    integer :: near_pairs = 0                   !< pairs that may come near in the current step
    logical, allocatable :: was_single(:)       !< (n): took the one-step update in the last step
    integer(i8) :: misses = 0_i8                !< pairs found within g0 with a body that took the one-step update
    type(broad_phase_t) :: finder
    real(wp), allocatable :: positions(:,:), speed(:)   !< scratch (3, n), (n)
  end type near_bodies_t

contains

  !> The members for a fluid step dt from the system's current state and the fluid velocity at the
  !> centres at both ends of the step (3, n), with the broad phase's gap g0 (m) of a sub-step.
  subroutine near_bodies_find(near, system, fluid_start, fluid_end, dt, g0)
    type(near_bodies_t), intent(inout) :: near
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: fluid_start(:,:), fluid_end(:,:), dt, g0
    real(wp) :: relative, gap
    logical, allocatable :: member(:)
    integer :: n, i, j, p, single, near_pairs
    integer(i8) :: misses
    n = system%n
    if (.not. allocated(near%members)) then
      allocate(near%members(n), near%single(n), near%was_single(n), near%positions(3, n), near%speed(n))
      near%was_single = .false.
    end if
    do i = 1, n
      near%positions(:, i) = system%bodies(i)%position
      near%speed(i) = max(norm2(system%bodies(i)%velocity), norm2(fluid_start(:, i)), norm2(fluid_end(:, i)))
    end do
    call broad_phase_find(near%finder, near%positions, system%bounding_radii, system%box_length, &
                          g0 + safety * dt * 2.0_wp * maxval(near%speed), share=rank_stride())
    allocate(member(n))
    member = .false.
    near_pairs = 0
    misses = 0_i8
    do p = 1, near%finder%count
      i = near%finder%first(p)
      j = near%finder%second(p)
      gap = bounding_gap(system, i, j)
      if (gap <= g0 .and. (near%was_single(i) .or. near%was_single(j))) misses = misses + 1_i8
      relative = max(norm2(system%bodies(j)%velocity - system%bodies(i)%velocity), &
                     norm2(fluid_start(:, j) - fluid_start(:, i)), norm2(fluid_end(:, j) - fluid_end(:, i)))
      if (gap > g0 + safety * dt * relative) cycle
      near_pairs = near_pairs + 1
      member(i) = .true.
      member(j) = .true.
    end do
    call any_of_ranks(member)
    near%near_pairs = sum_of_ranks(near_pairs)
    near%misses = near%misses + sum_of_ranks(misses)
    near%count = 0
    single = 0
    do i = 1, n
      if (member(i)) then
        near%count = near%count + 1
        near%members(near%count) = i
      else
        single = single + 1
        near%single(single) = i
      end if
    end do
    near%was_single = .not. member
  end subroutine near_bodies_find

  !> Gap (m) between the bounding spheres of bodies i and j (minimum image).
  real(wp) function bounding_gap(system, i, j)
    type(particle_system_t), intent(in) :: system
    integer, intent(in) :: i, j
    bounding_gap = norm2(minimum_image(system%bodies(j)%position - system%bodies(i)%position, system%box_length)) &
                   - (system%bounding_radii(i) + system%bounding_radii(j))
  end function bounding_gap
end module near_bodies
