!> Work on replicated data shared out over the ranks (docs/design.md, "Particle data across
!> ranks"): every rank holds every item, computes its share of them, and one collective makes the
!> results every rank's, bit for bit what one rank computing every item would hold.
!> - Blocks: items 1..n cut into one contiguous block per rank, in rank order (sizes differing by at
!>   most one); share_columns gathers the blocks' columns of an array.
!> - Strides: item i is rank mod(i - 1, ranks)'s, for work whose cost per item falls with i (a
!>   pair search over j > i) and would leave the first block the most; its results are combined by
!>   any_of_ranks (flags) and sum_of_ranks (counts).
module shared_work
  use mpi_f08, only: MPI_Allgatherv, MPI_Allreduce, MPI_IN_PLACE, MPI_DATATYPE_NULL, MPI_LOGICAL, MPI_LOR, &
                     MPI_SUM, MPI_INTEGER, MPI_INTEGER8
  use agglo_kinds, only: wp, i8
  use parallel_env, only: world, mpi_wp, my_rank, n_ranks
  implicit none
  private
  public :: rank_block, share_columns, rank_stride, any_of_ranks, sum_of_ranks

  interface sum_of_ranks
    module procedure sum_of_ranks_integer, sum_of_ranks_i8
  end interface sum_of_ranks

contains

  !> first..last: the block of items 1..n that rank `rank` (default: this rank) computes; empty
  !> (last = first - 1) when there are more ranks than items.
  pure subroutine rank_block(n, first, last, rank)
    integer, intent(in) :: n
    integer, intent(out) :: first, last
    integer, intent(in), optional :: rank
    integer :: r
    r = my_rank
    if (present(rank)) r = rank
    first = int(int(r, i8) * n / n_ranks) + 1
    last = int(int(r + 1, i8) * n / n_ranks)
  end subroutine rank_block

  !> Columns values(:, first..last) of every rank's block (rank_block of size(values, 2)) made
  !> every rank's (collective; nothing to do on one rank).
  subroutine share_columns(values)
    real(wp), intent(inout), contiguous :: values(:, :)
    integer :: counts(0:n_ranks - 1), offsets(0:n_ranks - 1), r, first, last
    if (n_ranks == 1) return
    do r = 0, n_ranks - 1
      call rank_block(size(values, 2), first, last, r)
      counts(r) = (last - first + 1) * size(values, 1)
      offsets(r) = (first - 1) * size(values, 1)
    end do
    call MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, values, counts, offsets, mpi_wp, world)
  end subroutine share_columns

  !> This rank's items by stride: i = share(1), share(1) + share(2), ... (share(1) = rank + 1,
  !> share(2) = ranks).
  pure function rank_stride() result(share)
    integer :: share(2)
    share = [my_rank + 1, n_ranks]
  end function rank_stride

  !> flags(i) = .true. where any rank's flags(i) is (collective).
  subroutine any_of_ranks(flags)
    logical, intent(inout) :: flags(:)
    if (n_ranks == 1) return
    call MPI_Allreduce(MPI_IN_PLACE, flags, size(flags), MPI_LOGICAL, MPI_LOR, world)
  end subroutine any_of_ranks

  !> The sum over ranks of an integer count (collective).
  integer function sum_of_ranks_integer(local) result(total)
    integer, intent(in) :: local
    total = local
    if (n_ranks > 1) call MPI_Allreduce(MPI_IN_PLACE, total, 1, MPI_INTEGER, MPI_SUM, world)
  end function sum_of_ranks_integer

  integer(i8) function sum_of_ranks_i8(local) result(total)
    integer(i8), intent(in) :: local
    total = local
    if (n_ranks > 1) call MPI_Allreduce(MPI_IN_PLACE, total, 1, MPI_INTEGER8, MPI_SUM, world)
  end function sum_of_ranks_i8
end module shared_work
