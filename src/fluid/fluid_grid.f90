!> The periodic box and its staggered (MAC) grid, decomposed in z slabs as FFTW-MPI needs.
!>
!> Cell (i,j,k), 1-based global indices, has its centre at ((i-1/2)dx, (j-1/2)dy, (k-1/2)dz);
!> pressure lives there. u(i,j,k) is at (i dx, (j-1/2)dy, (k-1/2)dz) (the cell's +x face),
!> v(i,j,k) at ((i-1/2)dx, j dy, (k-1/2)dz), w(i,j,k) at ((i-1/2)dx, (j-1/2)dy, k dz).
!> Rank r holds global k = z_offset+1 .. z_offset+nz_local; its fields are allocated
!> (0:nx+1, 0:ny+1, 0:nz_local+1) with one halo layer on each side (local k index).
module fluid_grid
  use agglo_kinds, only: wp
  use slab_decomposition, only: slab_t, slab_create
  use halo_exchange, only: exchange_slab_halos
  implicit none
  private
  public :: fluid_grid_t, grid_create, allocate_field, exchange_halos, &
            x_centre, y_centre, z_centre, x_face, y_face, z_face

  type :: fluid_grid_t
    integer :: nx = 0, ny = 0, nz = 0            !< global cells per direction
    real(wp) :: lx = 0, ly = 0, lz = 0           !< m, box edge lengths
    real(wp) :: dx = 0, dy = 0, dz = 0           !< m, cell sizes
    integer :: nz_local = 0                      !< z planes on this rank
    integer :: z_offset = 0                      !< global k = z_offset + local k
    real(wp) :: cell_volume = 0                  !< m^3
    integer :: cells_total = 0                   !< nx ny nz (fits default integers up to 1290^3)
    type(slab_t) :: slab                         !< decomposition details, FFT layout and halo buffers
  end type fluid_grid_t

contains

  !> Build the grid and this rank's slab (collective over MPI_COMM_WORLD).
  subroutine grid_create(grid, nx, ny, nz, lx, ly, lz)
    type(fluid_grid_t), intent(out) :: grid
    integer, intent(in) :: nx, ny, nz
    real(wp), intent(in) :: lx, ly, lz
    grid%nx = nx; grid%ny = ny; grid%nz = nz
    grid%lx = lx; grid%ly = ly; grid%lz = lz
    grid%dx = lx / nx; grid%dy = ly / ny; grid%dz = lz / nz
    grid%cell_volume = grid%dx * grid%dy * grid%dz
    grid%cells_total = nx * ny * nz
    call slab_create(grid%slab, nx, ny, nz)
    grid%nz_local = grid%slab%nz_local
    grid%z_offset = grid%slab%z_offset
  end subroutine grid_create

  !> A field with its halo layer, (0:nx+1, 0:ny+1, 0:nz_local+1), set to zero.
  subroutine allocate_field(grid, field)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), allocatable, intent(inout) :: field(:, :, :)
    if (allocated(field)) deallocate(field)
    allocate(field(0:grid%nx + 1, 0:grid%ny + 1, 0:grid%nz_local + 1))
    field = 0.0_wp
  end subroutine allocate_field

  !> Fill the halo layer of a field from its periodic images / neighbouring slabs (collective).
  subroutine exchange_halos(grid, field)
    type(fluid_grid_t), intent(inout) :: grid
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    call exchange_slab_halos(grid%slab, field)
  end subroutine exchange_halos

  !> Positions (m) of cell centres and faces; i, j global, k local to this rank's slab.
  pure real(wp) function x_centre(grid, i)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: i
    x_centre = (i - 0.5_wp) * grid%dx
  end function x_centre

  pure real(wp) function y_centre(grid, j)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: j
    y_centre = (j - 0.5_wp) * grid%dy
  end function y_centre

  pure real(wp) function z_centre(grid, k)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: k
    z_centre = (grid%z_offset + k - 0.5_wp) * grid%dz
  end function z_centre

  pure real(wp) function x_face(grid, i)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: i
    x_face = i * grid%dx
  end function x_face

  pure real(wp) function y_face(grid, j)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: j
    y_face = j * grid%dy
  end function y_face

  pure real(wp) function z_face(grid, k)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: k
    z_face = (grid%z_offset + k) * grid%dz
  end function z_face
end module fluid_grid
