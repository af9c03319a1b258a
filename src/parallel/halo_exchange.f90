!> Halo exchange of slab-decomposed periodic fields allocated (0:nx+1, 0:ny+1, 0:nz_local+1):
!> x and y halos are periodic copies inside the rank, z halos come from the neighbouring slabs.
!> The z planes are sent whole (with their x-y halo ring), so edge and corner halos are right too.
!> Buffers are the slab's own preallocated planes: nothing is allocated here.
!>
!> Why more than one entry point (docs/studies/performance.md, Fluid): each MPI message is a point where
!> the two ranks wait for each other, which on a shared machine costs more than the bytes. So
!> exchange_z_halos sends up to three fields (u, v, w) in ONE message per direction, both
!> directions in flight at once, and start_plane_shift / finish_plane_shift move a single plane
!> without blocking, so the caller can overlap the message with interior work.
module halo_exchange
  use mpi_f08, only: MPI_Isend, MPI_Irecv, MPI_Waitall, MPI_STATUSES_IGNORE, MPI_F_sync_reg
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp, n_ranks
  use error_handling, only: fatal
  use slab_decomposition, only: slab_t
  implicit none
  private
  public :: exchange_slab_halos, exchange_z_halos, start_plane_shift, finish_plane_shift

  integer, parameter :: tag_up = 101, tag_down = 102

contains

  !> All halos of one to three fields: x and y periodic copies, then the z planes (one message
  !> per direction for all the fields).
  subroutine exchange_slab_halos(slab, a, b, c)
    type(slab_t), intent(inout) :: slab
    real(wp), intent(inout) :: a(0:, 0:, 0:)
    real(wp), intent(inout), optional :: b(0:, 0:, 0:), c(0:, 0:, 0:)
    call periodic_xy(a)
    if (present(b)) call periodic_xy(b)
    if (present(c)) call periodic_xy(c)
    call exchange_z_halos(slab, a, b, c)

  contains

    !> Periodic in x, then in y over the full x range (fills the x-y edge halos).
    subroutine periodic_xy(field)
      real(wp), intent(inout) :: field(0:, 0:, 0:)
      integer :: nx, ny, nzl
      nx = slab%nx; ny = slab%ny; nzl = slab%nz_local
      field(0, 1:ny, 1:nzl) = field(nx, 1:ny, 1:nzl)
      field(nx + 1, 1:ny, 1:nzl) = field(1, 1:ny, 1:nzl)
      field(:, 0, 1:nzl) = field(:, ny, 1:nzl)
      field(:, ny + 1, 1:nzl) = field(:, 1, 1:nzl)
    end subroutine periodic_xy
  end subroutine exchange_slab_halos

  !> The z halo planes (0 and nz_local+1) of one to three fields; the x-y halos of planes 1 and
  !> nz_local must already be current (the planes travel whole). One message per direction
  !> carries all the fields; both directions are posted before waiting.
  subroutine exchange_z_halos(slab, a, b, c)
    type(slab_t), intent(inout) :: slab
    real(wp), intent(inout) :: a(0:, 0:, 0:)
    real(wp), intent(inout), optional :: b(0:, 0:, 0:), c(0:, 0:, 0:)
    integer :: nzl, plane, fields
    nzl = slab%nz_local
    if (n_ranks == 1) then
      call wrap(a)
      if (present(b)) call wrap(b)
      if (present(c)) call wrap(c)
      return
    end if
    plane = (slab%nx + 2) * (slab%ny + 2)
    fields = 1
    call pack_plane(a, nzl, slab%send_up(1:plane)); call pack_plane(a, 1, slab%send_down(1:plane))
    if (present(b)) then
      call pack_plane(b, nzl, slab%send_up(fields * plane + 1:(fields + 1) * plane))
      call pack_plane(b, 1, slab%send_down(fields * plane + 1:(fields + 1) * plane))
      fields = fields + 1
    end if
    if (present(c)) then
      call pack_plane(c, nzl, slab%send_up(fields * plane + 1:(fields + 1) * plane))
      call pack_plane(c, 1, slab%send_down(fields * plane + 1:(fields + 1) * plane))
      fields = fields + 1
    end if
    call post_both(slab, fields * plane)
    call wait_all(slab)
    fields = 1
    call unpack_plane(slab%receive_below(1:plane), 0, a); call unpack_plane(slab%receive_above(1:plane), nzl + 1, a)
    if (present(b)) then
      call unpack_plane(slab%receive_below(fields * plane + 1:(fields + 1) * plane), 0, b)
      call unpack_plane(slab%receive_above(fields * plane + 1:(fields + 1) * plane), nzl + 1, b)
      fields = fields + 1
    end if
    if (present(c)) then
      call unpack_plane(slab%receive_below(fields * plane + 1:(fields + 1) * plane), 0, c)
      call unpack_plane(slab%receive_above(fields * plane + 1:(fields + 1) * plane), nzl + 1, c)
    end if

  contains

    subroutine wrap(field)
      real(wp), intent(inout) :: field(0:, 0:, 0:)
      field(:, :, 0) = field(:, :, nzl)
      field(:, :, nzl + 1) = field(:, :, 1)
    end subroutine wrap
  end subroutine exchange_z_halos

  !> Start sending one plane (any contiguous 2-D array no larger than an x-y plane with its halo
  !> ring) to the slab above (upward) or below, and receiving the same-sized plane from the other
  !> neighbour. Non-blocking: finish_plane_shift delivers it. On one rank the plane is its own
  !> periodic image and is simply copied.
  subroutine start_plane_shift(slab, plane, upward)
    type(slab_t), intent(inout) :: slab
    real(wp), intent(in), contiguous :: plane(:, :)
    logical, intent(in) :: upward
    integer :: count
    count = size(plane)
    if (count > size(slab%send_up)) call fatal('start_plane_shift: plane larger than the halo buffers', &
                                               collective=.false.)
    if (slab%pending /= 0) call fatal('start_plane_shift: a halo exchange is already in flight', &
                                      collective=.false.)
    if (upward) then
      call plane_to_buffer(plane, slab%send_up)
      if (n_ranks == 1) then
        slab%receive_below(1:count) = slab%send_up(1:count)
        return
      end if
      call MPI_Irecv(slab%receive_below, count, mpi_wp, slab%rank_below, tag_up, world, slab%requests(1))
      call MPI_Isend(slab%send_up, count, mpi_wp, slab%rank_above, tag_up, world, slab%requests(2))
    else
      call plane_to_buffer(plane, slab%send_down)
      if (n_ranks == 1) then
        slab%receive_above(1:count) = slab%send_down(1:count)
        return
      end if
      call MPI_Irecv(slab%receive_above, count, mpi_wp, slab%rank_above, tag_down, world, slab%requests(1))
      call MPI_Isend(slab%send_down, count, mpi_wp, slab%rank_below, tag_down, world, slab%requests(2))
    end if
    slab%pending = 2
  end subroutine start_plane_shift

  !> Wait for the plane started by start_plane_shift (same upward flag) and copy it into plane.
  subroutine finish_plane_shift(slab, plane, upward)
    type(slab_t), intent(inout) :: slab
    real(wp), intent(inout), contiguous :: plane(:, :)
    logical, intent(in) :: upward
    integer :: i, j, n
    call wait_all(slab)
    n = 0
    do j = 1, size(plane, 2)
      do i = 1, size(plane, 1)
        n = n + 1
        if (upward) then
          plane(i, j) = slab%receive_below(n)
        else
          plane(i, j) = slab%receive_above(n)
        end if
      end do
    end do
  end subroutine finish_plane_shift

  !> Copy a 2-D plane into the first size(plane) entries of a buffer (explicit loops: no temporary).
  subroutine plane_to_buffer(plane, buffer)
    real(wp), intent(in) :: plane(:, :)
    real(wp), intent(inout) :: buffer(:)
    integer :: i, j, n
    n = 0
    do j = 1, size(plane, 2)
      do i = 1, size(plane, 1)
        n = n + 1
        buffer(n) = plane(i, j)
      end do
    end do
  end subroutine plane_to_buffer

  !> Post the receives of both z halos and the sends of both boundary planes (count reals each).
  subroutine post_both(slab, count)
    type(slab_t), intent(inout) :: slab
    integer, intent(in) :: count
    if (slab%pending /= 0) call fatal('exchange_z_halos: a halo exchange is already in flight', &
                                      collective=.false.)
    call MPI_Irecv(slab%receive_below, count, mpi_wp, slab%rank_below, tag_up, world, slab%requests(1))
    call MPI_Irecv(slab%receive_above, count, mpi_wp, slab%rank_above, tag_down, world, slab%requests(2))
    call MPI_Isend(slab%send_up, count, mpi_wp, slab%rank_above, tag_up, world, slab%requests(3))
    call MPI_Isend(slab%send_down, count, mpi_wp, slab%rank_below, tag_down, world, slab%requests(4))
    slab%pending = 4
  end subroutine post_both

  !> Complete the requests in flight. MPI_F_sync_reg tells the compiler the receive buffers
  !> changed behind its back (MPI 3.1 section 17.1.17), so no stale register copy is used.
  subroutine wait_all(slab)
    type(slab_t), intent(inout) :: slab
    if (slab%pending == 0) return
    call MPI_Waitall(slab%pending, slab%requests(1:slab%pending), MPI_STATUSES_IGNORE)
    slab%pending = 0
    call MPI_F_sync_reg(slab%receive_below)
    call MPI_F_sync_reg(slab%receive_above)
  end subroutine wait_all

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
