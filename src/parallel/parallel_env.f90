!> MPI start and stop, the rank layout, and the few global reductions everyone needs.
module parallel_env
  use mpi_f08, only: MPI_Comm, MPI_COMM_WORLD, MPI_Init, MPI_Finalize, MPI_Comm_rank, MPI_Comm_size, &
                     MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_MAX, MPI_DOUBLE_PRECISION, &
                     MPI_Datatype, MPI_Initialized, MPI_Barrier
  use agglo_kinds, only: wp
  use logger, only: log_set_rank
  implicit none
  private
  public :: parallel_start, parallel_stop, my_rank, n_ranks, is_root, world, mpi_wp, &
            global_sum, global_max, barrier

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
end module parallel_env
