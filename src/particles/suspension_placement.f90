!> Random placement of a suspension in a periodic box (docs/theory.md, "Suspension placement"):
!> random sequential addition. The bodies are placed one after the other, species by species in the
!> order given; each try draws a uniform centre in the box and a uniform orientation (quaternion
!> random_orientation, Shoemake 1992) and is kept when its surface gap to every body already placed is at
!> least min_gap, else drawn again, at most max_attempts times per body. The gap test of a try:
!>   1. the placed bodies in the 27 cells around the try (a cell list of the placed centres, cells
!>      no narrower than the largest bounding diameter plus min_gap, so no other body can be near);
!>   2. bounding spheres first (broad_phase near_pair: a pair whose spheres are more than min_gap
!>      apart is kept without more work);
!>   3. inscribed spheres: a pair whose inscribed spheres (radius min(a, b)) overlap is refused;
!>   4. otherwise the exact surface gap of the two spheroids (module closest_points) at the
!>      minimum image, refused below min_gap or when the closest points do not converge.
!> Every random number comes from one stream (the caller's, seeded from the run's seed), drawn in
!> the same order on every rank, so every rank places the same bodies.
module suspension_placement
  use agglo_kinds, only: wp, i8
  use random_stream, only: random_stream_t, stream_uniform, stream_normal
  use quaternion, only: random_orientation
  use periodic_box, only: image_shift
  use spheroid, only: spheroid_t
  use closest_points, only: closest_points_t, find_closest_points
  use broad_phase, only: near_pair
  implicit none
  private
  public :: placement_t, place_bodies, random_relative_velocities

  !> What a placement reached: all bodies, or how far it got.
  type :: placement_t
    logical :: complete = .false.
    integer :: placed = 0                         !< bodies placed (all of them when complete)
    integer(i8) :: attempts = 0_i8                !< tries in all
    integer :: exact_gaps = 0                     !< pairs that needed the exact spheroid gap
    real(wp) :: volume_fraction = 0.0_wp          !< of the bodies placed
    real(wp), allocatable :: centres(:,:)         !< (3, n) m, in [0, box)
    real(wp), allocatable :: quaternions(:,:)     !< (4, n) body -> lab
  end type placement_t

contains

  !> Place the bodies of shapes (in order) in the periodic box (box, m) with surface gaps >= min_gap.
  !> Stops at the first body that max_attempts tries cannot place (placement%complete false).
  subroutine place_bodies(shapes, box, min_gap, max_attempts, stream, placement)
    type(spheroid_t), intent(in) :: shapes(:)
    real(wp), intent(in) :: box(3), min_gap
    integer, intent(in) :: max_attempts
    type(random_stream_t), intent(inout) :: stream
    type(placement_t), intent(out) :: placement
    real(wp) :: reach(size(shapes)), width, try_centre(3), try_q(4), placed_volume
    integer :: cells(3), n, i, attempt
    integer, allocatable :: head(:), next(:)
    logical :: accepted
    n = size(shapes)
    allocate(placement%centres(3, n), placement%quaternions(4, n), next(n))
    placement%centres = 0
    placement%quaternions = 0
    do i = 1, n
      reach(i) = max(shapes(i)%a, shapes(i)%b)
    end do
    ! Cells at least as wide as the largest bounding diameter plus the gap: every body that may be
    ! near a try has its centre in the try's cell or a neighbour. At most about 2 n + 1 cells.
    width = min_gap
    if (n > 0) width = width + 2.0_wp * maxval(reach)
    width = max(width, (product(box) / (2.0_wp * n + 1.0_wp))**(1.0_wp / 3.0_wp))
    cells = max(1, int(box / width))
    allocate(head(product(cells)))
    head = 0
    next = 0
    placed_volume = 0
    do i = 1, n
      accepted = .false.
      do attempt = 1, max_attempts
        placement%attempts = placement%attempts + 1
        try_centre = [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)] * box
        try_q = random_orientation(stream)
        if (clear_of_placed(i, try_centre, try_q)) then
          accepted = .true.
          exit
        end if
      end do
      if (.not. accepted) exit
      placement%centres(:, i) = try_centre
      placement%quaternions(:, i) = try_q
      call insert(i)
      placement%placed = i
      placed_volume = placed_volume + shapes(i)%volume
    end do
    placement%complete = placement%placed == n
    placement%volume_fraction = placed_volume / product(box)

  contains

    integer function cell_of(centre)
      real(wp), intent(in) :: centre(3)
      integer :: c(3)
      c = min(cells - 1, max(0, int(centre / box * cells)))
      cell_of = 1 + c(1) + cells(1) * (c(2) + cells(2) * c(3))
    end function cell_of

    subroutine insert(body)
      integer, intent(in) :: body
      integer :: k
      k = cell_of(placement%centres(:, body))
      next(body) = head(k)
      head(k) = body
    end subroutine insert

    !> Is a try of body i at centre with orientation q at least min_gap from every placed body?
    logical function clear_of_placed(i, centre, q)
      integer, intent(in) :: i
      real(wp), intent(in) :: centre(3), q(4)
      integer :: c(3), offsets(3, 3), counts(3), d, ox, oy, oz, j, k
      c = min(cells - 1, max(0, int(centre / box * cells)))
      ! The distinct neighbour cells per direction (one or two when the box holds fewer than 3 cells).
      do d = 1, 3
        select case (cells(d))
        case (1)
          counts(d) = 1
          offsets(1, d) = 0
        case (2)
          counts(d) = 2
          offsets(1:2, d) = [0, 1]
        case default
          counts(d) = 3
          offsets(:, d) = modulo(c(d) + [-1, 0, 1], cells(d))
        end select
      end do
      clear_of_placed = .false.
      do oz = 1, counts(3)
        do oy = 1, counts(2)
          do ox = 1, counts(1)
            k = 1 + offsets(ox, 1) + cells(1) * (offsets(oy, 2) + cells(2) * offsets(oz, 3))
            j = head(k)
            do while (j > 0)
              if (.not. pair_clear(i, centre, q, j)) return
              j = next(j)
            end do
          end do
        end do
      end do
      clear_of_placed = .true.
    end function clear_of_placed

    logical function pair_clear(i, centre, q, j)
      integer, intent(in) :: i, j
      real(wp), intent(in) :: centre(3), q(4)
      real(wp) :: image(3)
      type(closest_points_t) :: contact
      pair_clear = .true.
      if (.not. near_pair(centre, placement%centres(:, j), reach(i), reach(j), box, min_gap)) return
      pair_clear = .false.
      image = placement%centres(:, j) + image_shift(placement%centres(:, j) - centre, box)
      if (norm2(image - centre) < min(shapes(i)%a, shapes(i)%b) + min(shapes(j)%a, shapes(j)%b) + min_gap) return
      placement%exact_gaps = placement%exact_gaps + 1
      call find_closest_points(shapes(i), centre, q, shapes(j), image, placement%quaternions(:, j), contact)
      pair_clear = contact%converged .and. contact%gap >= min_gap
    end function pair_clear
  end subroutine place_bodies

  !> Random velocities of bodies of the given masses: each component normal with standard deviation
  !> rms, then the mass-weighted mean removed (no net momentum: a relative velocity).
  function random_relative_velocities(stream, masses, rms) result(velocities)
    type(random_stream_t), intent(inout) :: stream
    real(wp), intent(in) :: masses(:), rms
    real(wp) :: velocities(3, size(masses)), mean(3)
    integer :: i, d
    velocities = 0
    if (.not. (rms > 0.0_wp) .or. size(masses) == 0) return
    do i = 1, size(masses)
      do d = 1, 3
        velocities(d, i) = rms * stream_normal(stream)
      end do
    end do
    do d = 1, 3
      mean(d) = sum(masses * velocities(d, :)) / sum(masses)
      velocities(d, :) = velocities(d, :) - mean(d)
    end do
  end function random_relative_velocities
end module suspension_placement
