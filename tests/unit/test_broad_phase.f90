! checks: 15
!> Unit tests of broad_phase: the cell list finds exactly the pairs an independent brute force
!> finds (every pair i < j, every periodic image tried, the nearest kept) on random polydisperse
!> configurations: N from 2 to 3000, periodic cubes whose length is not a multiple of the cell
!> width, bodies on the box faces and corners, a box of exactly 3 cells per side, boxes of 2 and 1
!> cells per side, a slab (periodic in x and y only), no box at all, and a gap of huge() (every pair).
!> The pair lists must agree element by element, in the order (first, second) of the pair list.
!> A search shared out by stride (share = [s, 3], s = 1, 2, 3: shared_work's ranks) finds exactly the
!> whole search's pairs whose first body is s, s + 3, ..., in the same order.
program test_broad_phase
  use agglo_kinds, only: wp, i8
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use broad_phase, only: broad_phase_t, broad_phase_find
  use test_framework, only: test_start, test_finish, check
  implicit none
  real(wp), parameter :: r0 = 1.0_wp, gap = 0.3_wp   ! mean radius and gap (any unit)
  !> The cell-width floor of the module: 2 max(r) + gap with max(r) = 1.5 r0.
  real(wp), parameter :: width_min = 3.0_wp * r0 + gap
  type(random_stream_t) :: stream
  type(broad_phase_t) :: finder

  call test_start('broad_phase')
  call stream_seed(stream, 33_i8, 1)
  call compare(2, [0.0_wp, 0.0_wp, 0.0_wp], huge(1.0_wp), 0.0_wp, 'two_bodies_no_box_huge_gap', 1)
  call compare(500, [0.0_wp, 0.0_wp, 0.0_wp], gap, 0.0_wp, 'no_box_500', 0)
  call compare(10, spread(10.5_wp, 1, 3), gap, 0.0_wp, 'periodic_10', 0)
  call compare(200, spread(17.7_wp, 1, 3), gap, 0.0_wp, 'periodic_200', 0)
  call compare(1000, spread(29.9_wp, 1, 3), gap, 0.0_wp, 'periodic_1000', 0)
  call compare(3000, spread(43.1_wp, 1, 3), gap, 0.0_wp, 'periodic_3000', 0)
  call compare(3000, spread(43.1_wp, 1, 3), gap, 0.2_wp, 'periodic_3000_faces_and_corners', 0)
  call compare(3000, spread(43.1_wp, 1, 3), gap, 0.2_wp, 'periodic_3000_shared_by_stride', 0, strided=.true.)
  call compare(400, spread(3.2_wp * width_min, 1, 3), gap, 0.2_wp, 'three_cells_per_side', 3)
  call check(all(finder%cells == 3), 'three_cells_per_side_used')
  call compare(100, spread(2.5_wp * width_min, 1, 3), gap, 0.2_wp, 'two_cells_per_side', 2)
  call compare(50, spread(1.6_wp * width_min, 1, 3), gap, 0.2_wp, 'one_cell_per_side', 1)
  call compare(800, [25.3_wp, 19.1_wp, 0.0_wp], gap, 0.2_wp, 'slab_periodic_in_x_and_y', 0)
  call compare(300, spread(23.0_wp, 1, 3), huge(1.0_wp), 0.0_wp, 'huge_gap_every_pair', 1)
  ! O(N): the 3000 bodies are tested against the bodies of their neighbour cells only.
  call compare(3000, spread(43.1_wp, 1, 3), gap, 0.0_wp, 'periodic_3000_again', 0, quiet=.true.)
  call check(finder%tests < 3000_i8 * 2999_i8 / 2_i8 / 20_i8 .and. all(finder%cells >= 10), &
             'cell_list_tests_far_fewer_than_all_pairs')
  call test_finish()

contains

  !> n bodies of radius r0 (0.5 .. 1.5) at random in the box (or in a 40 r0 cube without a box);
  !> a fraction at_faces of them put on a face, an edge or a corner of the box (at 0 or just below
  !> L). expect_cells > 0: the cells per side the search must have used.
  subroutine compare(n, box_length, search_gap, at_faces, name, expect_cells, quiet, strided)
    integer, intent(in) :: n, expect_cells
    real(wp), intent(in) :: box_length(3), search_gap, at_faces
    character(len=*), intent(in) :: name
    logical, intent(in), optional :: quiet, strided
    real(wp) :: positions(3, n), radii(n), side(3)
    integer, allocatable :: first(:), second(:)
    logical, allocatable :: in_share(:)
    type(broad_phase_t) :: part
    integer :: i, k, s
    logical :: same
    character(len=120) :: detail
    side = merge(box_length, 40.0_wp * r0, box_length > 0.0_wp)
    do i = 1, n
      radii(i) = r0 * (0.5_wp + stream_uniform(stream))
      do k = 1, 3
        positions(k, i) = side(k) * stream_uniform(stream)
        if (box_length(k) > 0.0_wp .and. stream_uniform(stream) < at_faces) then
          ! On the face x = 0 or just inside x = L (positions of a wrapped system lie in [0, L)).
          positions(k, i) = merge(0.0_wp, box_length(k) * (1.0_wp - epsilon(1.0_wp)), stream_uniform(stream) < 0.5_wp)
        end if
      end do
    end do
    call reference_pairs(positions, radii, box_length, search_gap, first, second)
    call broad_phase_find(finder, positions, radii, box_length, search_gap)
    same = finder%count == size(first)
    if (same) same = all(finder%first(1:finder%count) == first) .and. all(finder%second(1:finder%count) == second)
    if (expect_cells > 0) same = same .and. all(pack(finder%cells, box_length > 0.0_wp) == expect_cells)
    write(detail, '(a,i0,a,i0,a,3(i0,1x),a,i0)') 'pairs ', finder%count, ' (brute force ', size(first), &
        '), cells ', finder%cells, ', distance tests ', finder%tests
    if (present(quiet)) return
    if (present(strided)) then
      do s = 1, 3
        call broad_phase_find(part, positions, radii, box_length, search_gap, share=[s, 3])
        in_share = mod(first - 1, 3) == s - 1
        same = same .and. part%count == count(in_share) .and. count(in_share) > 0
        if (same) same = all(part%first(1:part%count) == pack(first, in_share)) .and. &
                         all(part%second(1:part%count) == pack(second, in_share))
      end do
    end if
    call check(same .and. size(first) > 0, name//'_equals_brute_force', trim(detail))
  end subroutine compare

  !> Every pair i < j whose bounding spheres are within the gap at the nearest periodic image,
  !> every image -1, 0, +1 of every periodic direction tried (independent of the module's
  !> minimum-image arithmetic; positions lie in [0, L), so one of them is the nearest).
  subroutine reference_pairs(positions, radii, box_length, search_gap, first, second)
    real(wp), intent(in) :: positions(:,:), radii(:), box_length(3), search_gap
    integer, allocatable, intent(out) :: first(:), second(:)
    integer :: i, j, a, b, c, count
    real(wp) :: nearest, shift(3)
    integer, allocatable :: f(:), s(:)
    integer :: range(3)
    range = merge(1, 0, box_length > 0.0_wp)
    allocate(f(size(radii) * 64), s(size(radii) * 64))
    count = 0
    do i = 1, size(radii) - 1
      do j = i + 1, size(radii)
        nearest = huge(1.0_wp)
        do a = -range(1), range(1)
          do b = -range(2), range(2)
            do c = -range(3), range(3)
              shift = [a, b, c] * box_length
              nearest = min(nearest, norm2(positions(:, j) + shift - positions(:, i)))
            end do
          end do
        end do
        if (nearest - (radii(i) + radii(j)) > search_gap) cycle
        count = count + 1
        if (count > size(f)) then
          f = [f, f]
          s = [s, s]
        end if
        f(count) = i
        s(count) = j
      end do
    end do
    first = f(1:count)
    second = s(1:count)
  end subroutine reference_pairs

end program test_broad_phase
