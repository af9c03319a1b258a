!> Halo exchange of a slab-decomposed periodic field allocated (0:nx+1, 0:ny+1, 0:nz_local+1):
!> x and y halos are periodic copies inside the rank, z halos come from the neighbouring slabs.
!> The z planes are sent whole (with their x-y halo ring), so edge and corner halos are right too.
!> Buffers are the slab's own preallocated planes: nothing is allocated here.
module halo_exchange
  use mpi_f08, only: MPI_Sendrecv, MPI_STATUS_IGNORE
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp, n_ranks
  use slab_decomposition, only: slab_t
  implicit none
  private
  public :: exchange_slab_halos

  integer, parameter :: tag_up = 101, tag_down = 102

contains

  subroutine exchange_slab_halos(slab, field)
    type(slab_t), intent(inout) :: slab
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: nx, ny, nzl, plane
    nx = slab%nx; ny = slab%ny; nzl = slab%nz_local
    plane = (nx + 2) * (ny + 2)
    ! Periodic in x, then in y over the full x range (fills the x-y edge halos).
    field(0, 1:ny, 1:nzl) = field(nx, 1:ny, 1:nzl)
    field(nx + 1, 1:ny, 1:nzl) = field(1, 1:ny, 1:nzl)
    field(:, 0, 1:nzl) = field(:, ny, 1:nzl)
    field(:, ny + 1, 1:nzl) = field(:, 1, 1:nzl)
    if (n_ranks == 1) then
      field(:, :, 0) = field(:, :, nzl)
      field(:, :, nzl + 1) = field(:, :, 1)
      return
    end if
    ! Top plane goes up, the lower halo comes from below.
    call pack_plane(field, nzl, slab%send_buffer)
    call MPI_Sendrecv(slab%send_buffer, plane, mpi_wp, slab%rank_above, tag_up, &
                      slab%receive_buffer, plane, mpi_wp, slab%rank_below, tag_up, world, MPI_STATUS_IGNORE)
    call unpack_plane(slab%receive_buffer, 0, field)
    ! Bottom plane goes down, the upper halo comes from above.
    call pack_plane(field, 1, slab%send_buffer)
    call MPI_Sendrecv(slab%send_buffer, plane, mpi_wp, slab%rank_below, tag_down, &
                      slab%receive_buffer, plane, mpi_wp, slab%rank_above, tag_down, world, MPI_STATUS_IGNORE)
    call unpack_plane(slab%receive_buffer, nzl + 1, field)
  end subroutine exchange_slab_halos

  !> Copy plane k (with its halo ring) into a contiguous buffer.
  subroutine pack_plane(field, k, buffer)
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: k
    real(wp), intent(out) :: buffer(:)
    integer :: i, j, n
    n = 0
    do j = 0, ubound(field, 2)
      do i = 0, ubound(field, 1)
        n = n + 1
        buffer(n) = field(i, j, k)
      end do
    end do
  end subroutine pack_plane

  subroutine unpack_plane(buffer, k, field)
    real(wp), intent(in) :: buffer(:)
    integer, intent(in) :: k
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: i, j, n
    n = 0
    do j = 0, ubound(field, 2)
      do i = 0, ubound(field, 1)
        n = n + 1
        field(i, j, k) = buffer(n)
      end do
    end do
  end subroutine unpack_plane
end module halo_exchange
