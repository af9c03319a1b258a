!> Slab decomposition of a periodic nx x ny x nz grid along z, exactly as FFTW-MPI lays out a
!> 3-D real-to-complex transform with transposed output: in real space rank r owns the z planes
!> z_offset+1 .. z_offset+nz_local (the last Fortran index); in Fourier space (after the
!> transpose FFTW does for us) it owns the y lines y_offset_spectral+1 .. +ny_local_spectral.
!> The layout is taken from fftw_mpi_local_size_3d_transposed, so the solver never redistributes.
module slab_decomposition
  use, intrinsic :: iso_c_binding, only: c_intptr_t
  use mpi_f08, only: MPI_Request
  use fftw_interface, only: fftw_mpi_init, fftw_mpi_local_size_3d_transposed
  use agglo_kinds, only: wp
  use parallel_env, only: world, my_rank, n_ranks
  use error_handling, only: fatal
  implicit none
  private
  public :: slab_t, slab_create

  type :: slab_t
    integer :: nx = 0, ny = 0, nz = 0            !< global cells
    integer :: nz_local = 0, z_offset = 0        !< real-space slab: global k = z_offset + 1 .. z_offset + nz_local
    integer :: ny_local_spectral = 0             !< Fourier-space slab (transposed): global j = y_offset_spectral + 1 ..
    integer :: y_offset_spectral = 0
    integer(c_intptr_t) :: complex_alloc = 0     !< complex numbers FFTW needs in the in-place buffer of this rank
    integer :: rank_below = 0, rank_above = 0    !< neighbours in z (periodic)
    ! Halo buffers, allocated once (halo_exchange allocates nothing). Each holds up to
    ! max_halo_fields x-y planes with their halo ring, so u, v, w travel in one message per direction.
    real(wp), allocatable :: send_up(:), send_down(:), receive_below(:), receive_above(:)
    type(MPI_Request) :: requests(4)             !< the non-blocking exchange in flight (halo_exchange)
    integer :: pending = 0                       !< requests in flight (0: none)
  end type slab_t

  integer, parameter, public :: max_halo_fields = 3

contains

  !> The slab of this rank; fatal if FFTW would leave a rank without planes (the deck check
  !> requires nz and ny to be multiples of the rank count, which makes the slabs equal).
  subroutine slab_create(slab, nx, ny, nz)
    type(slab_t), intent(out) :: slab
    integer, intent(in) :: nx, ny, nz
    integer(c_intptr_t) :: local_n0, local_0_start, local_n1, local_1_start
    character(len=160) :: text
    ! Needed before any other FFTW-MPI call; further calls have no effect (FFTW manual, "MPI
    ! Initialization"), so no flag records the first.
    call fftw_mpi_init()
    slab%nx = nx; slab%ny = ny; slab%nz = nz
    ! FFTW takes dimensions in C order (slowest first): (nz, ny, nx/2 + 1) complex for r2c.
    slab%complex_alloc = fftw_mpi_local_size_3d_transposed(int(nz, c_intptr_t), int(ny, c_intptr_t), &
        int(nx / 2 + 1, c_intptr_t), world%MPI_VAL, local_n0, local_0_start, local_n1, local_1_start)
    slab%nz_local = int(local_n0)
    slab%z_offset = int(local_0_start)
    slab%ny_local_spectral = int(local_n1)
    slab%y_offset_spectral = int(local_1_start)
    if (slab%nz_local < 1 .or. slab%ny_local_spectral < 1) then
      write(text, '(a,i0,a,i0,a,i0,a)') 'slab decomposition: rank ', my_rank, ' of ', n_ranks, &
          ' got no planes of the ', nz, '-plane grid (nz and ny must be multiples of the rank count)'
      call fatal(trim(text), collective=.false.)
    end if
    slab%rank_below = modulo(my_rank - 1, n_ranks)
    slab%rank_above = modulo(my_rank + 1, n_ranks)
    allocate(slab%send_up(max_halo_fields * (nx + 2) * (ny + 2)), slab%send_down(max_halo_fields * (nx + 2) * (ny + 2)), &
             slab%receive_below(max_halo_fields * (nx + 2) * (ny + 2)), &
             slab%receive_above(max_halo_fields * (nx + 2) * (ny + 2)))
  end subroutine slab_create
end module slab_decomposition
