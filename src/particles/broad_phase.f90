!> Broad phase of the particle system (docs/theory.md, "Particle system"): every pair i < j whose
!> bounding spheres (radius r_i, e.g. max(a, b) of a spheroid) are within a gap g of each other,
!>   |x_j - x_i|_min - (r_i + r_j) <= g   (minimum image in periodic directions),
!> found with a cell list (linked cells; Allen & Tildesley, Computer Simulation of Liquids, 1987,
!> section 5.3) in O(N) per search at fixed number density.
!>
!> Cells: per direction n_c = floor(extent / w_min) cells of width w = extent / n_c >= w_min, with
!> w_min = 2 max(r) + g the largest separation of centres a near pair can have; the extent is the
!> period L in a periodic direction and the span of the centres in an unbounded one. So a near pair
!> lies in the same or in adjacent cells (across the period), and each body is tested against the
!> bodies of its 27 neighbour cells only. Fewer than 3 cells across a period: the distinct cells
!> only (2 cells: offsets 0 and 1; 1 cell: offset 0), so no pair is tested twice. The number of
!> cells is capped at max(27, 2 N) (wider cells, same result) so that a dilute set of small bodies
!> does not spend its time clearing empty cells. A gap so large that a single cell results (e.g.
!> huge(), the pair scenes) degenerates into the all-pairs loop with the same test.
!>
!> Result: first(1:count), second(1:count) sorted by (first, second), the order of the pair list
!> (1,2), (1,3), ..., (N-1,N) restricted to the near pairs. The near test is the same expression,
!> in the same floating-point operations, as the particle system's per-pair test (near_pair), so
!> the broad phase and brute force (all_near_pairs) agree exactly (the cell list's cheap pre-test,
!> surely_apart, only ever skips pairs that test is certain to find apart).
module broad_phase
  use agglo_kinds, only: wp, i8
  use periodic_box, only: image_shift
  implicit none
  private
  public :: broad_phase_t, broad_phase_find, all_near_pairs, near_pair

  !> Cell-list search state, kept between searches so that its arrays are reused.
  type :: broad_phase_t
    integer :: count = 0                         !< near pairs found by the last search
    integer, allocatable :: first(:), second(:)  !< (>= count): the pairs, sorted by (first, second)
    integer :: cells(3) = 1                      !< cells per direction of the last search
    integer(i8) :: tests = 0_i8                  !< distance tests of the last search (O(N) at fixed density)
    integer, allocatable :: head(:)              !< (cells): first body of each cell, 0 = empty
    integer, allocatable :: next(:)              !< (n): next body in the same cell, 0 = last
    integer, allocatable :: cell_of(:,:)         !< (3, n): the body's cell indices (0-based)
    integer, allocatable :: row(:)               !< scratch: the near partners j > i of one body
  end type broad_phase_t

contains

  !> Are the bounding spheres (radii radius_i, radius_j) of bodies at x_i and x_j within gap?
  !> x_j is taken at its minimum image next to x_i (image_shift; no shift where box_length = 0).
  pure logical function near_pair(position_i, position_j, radius_i, radius_j, box_length, gap)
    real(wp), intent(in) :: position_i(3), position_j(3), radius_i, radius_j, box_length(3), gap
    real(wp) :: image(3)
    image = position_j + image_shift(position_j - position_i, box_length)
    near_pair = .not. (norm2(image - position_i) - (radius_i + radius_j) > gap)
  end function near_pair

  !> A cheap pre-test of near_pair: .true. only when the centres are farther apart than reach
  !> (= radius_i + radius_j + gap) by a relative margin of 1e-9, far above the round-off by which
  !> this squared minimum-image distance can differ from near_pair's; so a pair it passes is far for
  !> near_pair too, and the exact test runs only for the few pairs that may be near.
  pure logical function surely_apart(position_i, position_j, reach, box_length)
    real(wp), intent(in) :: position_i(3), position_j(3), reach, box_length(3)
    real(wp) :: d, distance2, limit
    integer :: k
    surely_apart = .false.
    limit = reach * (1.0_wp + 1.0e-9_wp)
    if (.not. (limit < sqrt(huge(1.0_wp)))) return
    distance2 = 0.0_wp
    do k = 1, 3
      d = position_j(k) - position_i(k)
      if (box_length(k) > 0.0_wp) then
        if (d > 0.5_wp * box_length(k)) then
          d = d - box_length(k)
        else if (d < -0.5_wp * box_length(k)) then
          d = d + box_length(k)
        end if
        if (abs(d) > 0.5_wp * box_length(k)) return   ! not wrapped into the box: leave it to near_pair
      end if
      distance2 = distance2 + d * d
    end do
    surely_apart = distance2 > limit * limit
  end function surely_apart

  !> All near pairs by testing every pair i < j (the reference of the cell list; O(N^2)).
  subroutine all_near_pairs(positions, radii, box_length, gap, first, second)
    real(wp), intent(in) :: positions(:,:), radii(:), box_length(3), gap
    integer, allocatable, intent(out) :: first(:), second(:)
    integer :: i, j, count
    integer, allocatable :: a(:), b(:)
    allocate(a(0), b(0))
    count = 0
    do i = 1, size(radii) - 1
      do j = i + 1, size(radii)
        if (.not. near_pair(positions(:, i), positions(:, j), radii(i), radii(j), box_length, gap)) cycle
        count = count + 1
        if (count > size(a)) then
          a = [a, spread(0, 1, max(16, count))]
          b = [b, spread(0, 1, max(16, count))]
        end if
        a(count) = i
        b(count) = j
      end do
    end do
    first = a(1:count)
    second = b(1:count)
  end subroutine all_near_pairs

  !> The near pairs of bodies at positions (3, n) with bounding radii (n), periods box_length
  !> (0 = unbounded direction) and gap (m): finder%first(1:finder%count), finder%second(...).
  !> With share = [i0, stride], only the pairs whose first body is i0, i0 + stride, ... (a rank's
  !> share of the search: shared_work, rank_stride); the cells hold every body all the same.
  subroutine broad_phase_find(finder, positions, radii, box_length, gap, share)
    type(broad_phase_t), intent(inout) :: finder
    real(wp), intent(in) :: positions(:,:), radii(:), box_length(3), gap
    integer, intent(in), optional :: share(2)
    real(wp) :: width_min, origin(3), extent(3), width(3), scale, total
    integer :: n, k, i, j, c, ncells, count_i, offsets(3, 3), noffsets(3), a, b, d, cell(3)
    integer :: neighbour_cells(27), nneighbours, m, linear_offsets(27), nlinear
    logical :: inside
    integer :: first_body, stride
    n = size(radii)
    first_body = 1
    stride = 1
    if (present(share)) then
      first_body = share(1)
      stride = share(2)
    end if
    finder%count = 0
    finder%tests = 0_i8
    finder%cells = 1
    if (.not. allocated(finder%first)) allocate(finder%first(max(16, n)), finder%second(max(16, n)))
    if (n < 2) return
    ! A margin of a few ulps keeps a pair exactly w_min apart in adjacent cells despite the
    ! round-off of x / w (no margin needed, nor possible, for a gap near huge()).
    width_min = 2.0_wp * maxval(radii) + gap
    if (width_min < 0.5_wp * huge(1.0_wp)) width_min = width_min * (1.0_wp + 64.0_wp * epsilon(1.0_wp))
    ! Cells per direction: as many of width >= width_min as fit (at least 1).
    do k = 1, 3
      if (box_length(k) > 0.0_wp) then
        origin(k) = 0.0_wp
        extent(k) = box_length(k)
      else
        origin(k) = minval(positions(k, :))
        extent(k) = maxval(positions(k, :)) - origin(k)
      end if
      finder%cells(k) = 1
      if (width_min > 0.0_wp .and. extent(k) > 0.0_wp) &
        finder%cells(k) = max(1, int(min(extent(k) / width_min, 1.0e6_wp)))
    end do
    total = product(real(finder%cells, wp))
    if (total > real(max(27, 2 * n), wp)) then
      scale = (real(max(27, 2 * n), wp) / total)**(1.0_wp / 3.0_wp)
      finder%cells = max(1, int(real(finder%cells, wp) * scale))
    end if
    ncells = product(finder%cells)
    width = extent / real(finder%cells, wp)
    ! Neighbour offsets per direction: distinct cells only (see the module header).
    do k = 1, 3
      if (finder%cells(k) == 1) then
        noffsets(k) = 1
        offsets(:, k) = [0, 0, 0]
      else if (finder%cells(k) >= 3 .or. box_length(k) <= 0.0_wp) then
        noffsets(k) = 3
        offsets(:, k) = [-1, 0, 1]
      else
        noffsets(k) = 2
        offsets(:, k) = [0, 1, 0]
      end if
    end do
    ! Linked cells: bodies of each cell in decreasing order (filled from the first body), so that a
    ! body's search of a cell stops at the first partner j <= i: it never visits the others.
    if (allocated(finder%head)) then
      if (size(finder%head) < ncells) deallocate(finder%head)
    end if
    if (.not. allocated(finder%head)) allocate(finder%head(ncells))
    if (allocated(finder%next)) then
      if (size(finder%next) < n) deallocate(finder%next, finder%cell_of)
    end if
    if (.not. allocated(finder%next)) allocate(finder%next(n), finder%cell_of(3, n))
    if (.not. allocated(finder%row)) allocate(finder%row(64))
    finder%head(1:ncells) = 0
    do i = 1, n
      do k = 1, 3
        if (finder%cells(k) == 1) then
          cell(k) = 0
        else if (box_length(k) > 0.0_wp) then
          cell(k) = modulo(floor(positions(k, i) / width(k)), finder%cells(k))
        else
          cell(k) = min(finder%cells(k) - 1, max(0, floor((positions(k, i) - origin(k)) / width(k))))
        end if
      end do
      finder%cell_of(:, i) = cell
      c = linear_cell(cell, finder%cells)
      finder%next(i) = finder%head(c)
      finder%head(c) = i
    end do
    ! Linear offsets of the 27 neighbours of a cell that is at least one cell from every edge (no
    ! wrap needed): most cells of a large system.
    nlinear = 0
    if (all(noffsets == 3)) then
      do a = -1, 1
        do b = -1, 1
          do d = -1, 1
            nlinear = nlinear + 1
            linear_offsets(nlinear) = a + finder%cells(1) * (b + finder%cells(2) * d)
          end do
        end do
      end do
    end if
    do i = first_body, n - 1, stride
      ! The distinct neighbour cells of body i's cell.
      nneighbours = 0
      if (nlinear == 27) then
        if (all(finder%cell_of(:, i) >= 1 .and. finder%cell_of(:, i) <= finder%cells - 2)) then
          c = linear_cell(finder%cell_of(:, i), finder%cells)
          neighbour_cells = c + linear_offsets
          nneighbours = 27
        end if
      end if
      if (nneighbours == 0) then
        do a = 1, noffsets(1)
          do b = 1, noffsets(2)
            do d = 1, noffsets(3)
              cell = finder%cell_of(:, i) + [offsets(a, 1), offsets(b, 2), offsets(d, 3)]
              call wrap_cell(cell, finder%cells, box_length, inside)
              if (.not. inside) cycle
              nneighbours = nneighbours + 1
              neighbour_cells(nneighbours) = linear_cell(cell, finder%cells)
            end do
          end do
        end do
      end if
      count_i = 0
      do m = 1, nneighbours
        j = finder%head(neighbour_cells(m))
        do while (j > i)   ! the end of the list (0) or the first j <= i
          finder%tests = finder%tests + 1_i8
          if (.not. surely_apart(positions(:, i), positions(:, j), radii(i) + radii(j) + gap, box_length)) then
            if (near_pair(positions(:, i), positions(:, j), radii(i), radii(j), box_length, gap)) then
              count_i = count_i + 1
              if (count_i > size(finder%row)) finder%row = [finder%row, finder%row]
              finder%row(count_i) = j
            end if
          end if
          j = finder%next(j)
        end do
      end do
      if (count_i == 0) cycle
      call insertion_sort(finder%row(1:count_i))
      if (finder%count + count_i > size(finder%first)) then
        finder%first = [finder%first, spread(0, 1, max(size(finder%first), count_i))]
        finder%second = [finder%second, spread(0, 1, max(size(finder%second), count_i))]
      end if
      finder%first(finder%count + 1:finder%count + count_i) = i
      finder%second(finder%count + 1:finder%count + count_i) = finder%row(1:count_i)
      finder%count = finder%count + count_i
    end do
  end subroutine broad_phase_find

  !> 1-based linear index of a 0-based cell.
  pure integer function linear_cell(cell, cells)
    integer, intent(in) :: cell(3), cells(3)
    linear_cell = 1 + cell(1) + cells(1) * (cell(2) + cells(2) * cell(3))
  end function linear_cell

  !> Bring a neighbour cell into range: across the period in periodic directions; .false. when it
  !> lies outside the cells of an unbounded direction.
  pure subroutine wrap_cell(cell, cells, box_length, inside)
    integer, intent(inout) :: cell(3)
    integer, intent(in) :: cells(3)
    real(wp), intent(in) :: box_length(3)
    logical, intent(out) :: inside
    integer :: k
    inside = .true.
    do k = 1, 3
      if (box_length(k) > 0.0_wp) then
        ! Offsets are -1, 0, 1: one period at most (branches, not modulo: this is the inner loop).
        if (cell(k) < 0) then
          cell(k) = cell(k) + cells(k)
        else if (cell(k) >= cells(k)) then
          cell(k) = cell(k) - cells(k)
        end if
      else if (cell(k) < 0 .or. cell(k) >= cells(k)) then
        inside = .false.
      end if
    end do
  end subroutine wrap_cell

  !> Sort a short list of body indices in increasing order.
  pure subroutine insertion_sort(list)
    integer, intent(inout) :: list(:)
    integer :: i, j, key
    do i = 2, size(list)
      key = list(i)
      j = i - 1
      do while (j >= 1)
        if (list(j) <= key) exit
        list(j + 1) = list(j)
        j = j - 1
      end do
      list(j + 1) = key
    end do
  end subroutine insertion_sort

end module broad_phase
