! ranks: 2
! checks: 7
!> shared_work on 2 ranks: the blocks and the strides cut the items into disjoint shares that cover
!> them all; share_columns gives every rank every block's columns as its owner computed them;
!> any_of_ranks and sum_of_ranks combine the ranks' flags and counts. The ranks fill their shares
!> with different values on purpose; each check holds on every rank
!> (test_framework's on_every_rank: a reduction of the test's own, not the routines under test).
program test_shared_work
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, my_rank, n_ranks
  use shared_work, only: rank_block, share_columns, rank_stride, any_of_ranks, sum_of_ranks
  use test_framework, only: test_start, test_finish, check, check_equal, on_every_rank
  implicit none
  integer, parameter :: sizes(5) = [0, 1, 2, 7, 100001]
  real(wp), allocatable :: values(:, :)
  logical, allocatable :: flags(:)
  integer :: share(2), k, i, first, last, covered
  logical :: ok

  call parallel_start()
  call test_start('shared_work')
  call check_equal(n_ranks, 2, 'runs_on_two_ranks')

  ! Blocks: rank 0's block ends where rank 1's begins, they span 1..n, sizes differ by at most one.
  ok = .true.
  do k = 1, size(sizes)
    call rank_block(sizes(k), first, last, rank=0)
    covered = last - first + 1
    ok = ok .and. first == 1
    i = last
    call rank_block(sizes(k), first, last, rank=1)
    ok = ok .and. first == i + 1 .and. last == sizes(k) .and. abs((last - first + 1) - covered) <= 1
  end do
  call check(on_every_rank(ok), 'blocks_cut_the_items_into_contiguous_shares')

  ! Strides: rank 0 the odd items, rank 1 the even ones.
  share = rank_stride()
  call check(on_every_rank(share(1) == my_rank + 1 .and. share(2) == 2), 'strides_alternate_between_ranks')

  ! share_columns: each rank computes its block, the others' columns hold garbage until shared.
  allocate(values(3, 1001))
  values = -1.0_wp
  call rank_block(size(values, 2), first, last)
  do i = first, last
    values(:, i) = column(i)
  end do
  call share_columns(values)
  ok = .true.
  do i = 1, size(values, 2)
    ok = ok .and. all(values(:, i) == column(i))   ! values moved, not computed: exact
  end do
  call check(on_every_rank(ok), 'share_columns_gives_every_rank_every_block')

  ! any_of_ranks: rank 0 flags the multiples of 2, rank 1 those of 3.
  allocate(flags(60))
  flags = [(mod(i, 2 + my_rank) == 0, i = 1, 60)]
  call any_of_ranks(flags)
  call check(on_every_rank(all(flags .eqv. [(mod(i, 2) == 0 .or. mod(i, 3) == 0, i = 1, 60)])), &
             'any_of_ranks_is_the_union_of_the_flags')

  call check(on_every_rank(sum_of_ranks(my_rank + 1) == 3), 'sum_of_ranks_adds_the_counts')
  call check(on_every_rank(sum_of_ranks(2_i8**40 + my_rank) == 2_i8**41 + 1_i8), 'sum_of_ranks_adds_long_counts')
  call test_finish()

contains

  !> The values of column i (distinct for every i and row).
  pure function column(i) result(c)
    integer, intent(in) :: i
    real(wp) :: c(3)
    c = [real(i, wp), 1.0_wp / real(i, wp), sqrt(real(i, wp))]
  end function column
end program test_shared_work
