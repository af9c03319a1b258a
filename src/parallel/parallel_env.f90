!> MPI start and stop, the rank layout, and the few global reductions everyone needs.
module parallel_env
  use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_Init, MPI_Finalize, MPI_Comm_rank, MPI_Comm_size, &
                     MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_MAX, MPI_DOUBLE_PRECISION, &
                     MPI_Datatype, MPI_Initialized, MPI_Barrier, MPI_LOGICAL, MPI_LAND, MPI_LOR, MPI_Bcast, &
                     MPI_INTEGER, MPI_CHARACTER
  use agglo_kinds, only: wp
  use logger, only: log_set_rank
  implicit none
  private
  public :: parallel_start, parallel_stop, my_rank, n_ranks, is_root, world, mpi_wp, &
            global_sum, global_max, barrier, all_ranks, any_rank, root_text

  integer, protected :: my_rank = 0
  integer, protected :: n_ranks = 1
  type(MPI_Comm), protected :: world
  type(MPI_Datatype), parameter :: mpi_wp = MPI_DOUBLE_PRECISION   !< the MPI type of real(wp)

contains

  subroutine parallel_start()
    logical :: started
    call MPI_Initialized(started)
    if (.not. started) call MPI_Init()
    world = MPI_COMM_WORLD
    call MPI_Comm_rank(world, my_rank)
    call MPI_Comm_size(world, n_ranks)
    call log_set_rank(my_rank)
  end subroutine parallel_start

  subroutine parallel_stop()
    call MPI_Finalize()
  end subroutine parallel_stop

  logical function is_root()
    is_root = (my_rank == 0)
  end function is_root

  function global_sum(local) result(total)
    real(wp), intent(in) :: local
    real(wp) :: total
    total = local
    call MPI_Allreduce(MPI_IN_PLACE, total, 1, mpi_wp, MPI_SUM, world)
  end function global_sum

  function global_max(local) result(total)
    real(wp), intent(in) :: local
    real(wp) :: total
    total = local
    call MPI_Allreduce(MPI_IN_PLACE, total, 1, mpi_wp, MPI_MAX, world)
  end function global_max

  subroutine barrier()
    call MPI_Barrier(world)
  end subroutine barrier

  !> .true. on every rank if local is .true. on every rank. Turns a check each rank makes for
  !> itself (a file it sees) into one answer, so that a failure stops every rank together.
  logical function all_ranks(local)
    logical, intent(in) :: local
    all_ranks = local
    call MPI_Allreduce(MPI_IN_PLACE, all_ranks, 1, MPI_LOGICAL, MPI_LAND, world)
  end function all_ranks

  !> .true. on every rank if local is .true. on at least one rank.
  logical function any_rank(local)
    logical, intent(in) :: local
    any_rank = local
    call MPI_Allreduce(MPI_IN_PLACE, any_rank, 1, MPI_LOGICAL, MPI_LOR, world)
  end function any_rank

  !> Rank 0's text on every rank (the other ranks' text is ignored), e.g. the verdict of a check
  !> only rank 0 makes ('' = passed), so that every rank stops on it together.
  function root_text(text) result(shared)
    character(len=*), intent(in) :: text
    character(len=:), allocatable :: shared
    integer :: length
    length = len(text)
    call MPI_Bcast(length, 1, MPI_INTEGER, 0, world)
    allocate(character(len=length) :: shared)
    if (my_rank == 0) shared = text
    if (length > 0) call MPI_Bcast(shared, length, MPI_CHARACTER, 0, world)
  end function root_text
end module parallel_env
