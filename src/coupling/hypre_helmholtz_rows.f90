!> The unknowns of one field on the slab-decomposed periodic grid as rows of a linear system, and
!> the Crank-Nicolson Helmholtz rows (I - c L_h) u = b, c = nu dt / 2, with L_h the periodic
!> 7-point Laplacian (docs/theory.md, "Linear solver (hypre)").
!>
!> Numbering: the node (i, j, k) of a field (1-based global indices, each component of the
!> velocity on its own staggered nodes, all nx ny nz of them in the periodic box) is global row
!> i + nx (j - 1) + nx ny (k - 1). z is slowest, so rank r's slab (global k = z_offset + 1 ..
!> z_offset + nz_local, fluid_grid) is the contiguous block of rows nx ny z_offset + 1 ..
!> nx ny (z_offset + nz_local), in rank order: hypre's IJ layout needs exactly that.
!> The three velocity components are independent systems (the mirror rows of the immersed
!> boundary couple nodes of one component only), solved one after the other on these rows.
module hypre_helmholtz_rows
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t
  use hypre_solver, only: sparse_rows_t, rows_local_count
  implicit none
  private
  public :: global_row, helmholtz_rows_create, helmholtz_rows_set_coefficient, field_to_rows, rows_to_field

  integer, parameter :: stencil_size = 7

contains

  !> The global row of node (i, j, k_global), indices wrapped periodically into the box.
  pure integer function global_row(grid, i, j, k_global)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: i, j, k_global
    global_row = 1 + modulo(i - 1, grid%nx) + grid%nx * (modulo(j - 1, grid%ny) + grid%ny * modulo(k_global - 1, grid%nz))
  end function global_row

  !> This rank's rows of (I - coefficient L_h); needs nx, ny, nz >= 3 (so the 7 columns differ).
  subroutine helmholtz_rows_create(grid, coefficient, rows)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: coefficient
    type(sparse_rows_t), intent(out) :: rows
    integer :: i, j, k, kg, row, entry
    rows%first_row = grid%nx * grid%ny * grid%z_offset + 1
    rows%last_row = grid%nx * grid%ny * (grid%z_offset + grid%nz_local)
    allocate(rows%row_start(rows_local_count(rows) + 1), rows%columns(stencil_size * rows_local_count(rows)), &
             rows%values(stencil_size * rows_local_count(rows)))
    row = 0
    entry = 0
    do k = 1, grid%nz_local
      kg = grid%z_offset + k
      do j = 1, grid%ny
        do i = 1, grid%nx
          row = row + 1
          rows%row_start(row) = entry + 1
          rows%columns(entry + 1:entry + stencil_size) = [global_row(grid, i, j, kg), &
              global_row(grid, i - 1, j, kg), global_row(grid, i + 1, j, kg), &
              global_row(grid, i, j - 1, kg), global_row(grid, i, j + 1, kg), &
              global_row(grid, i, j, kg - 1), global_row(grid, i, j, kg + 1)]
          entry = entry + stencil_size
        end do
      end do
    end do
    rows%row_start(row + 1) = entry + 1
    call helmholtz_rows_set_coefficient(grid, coefficient, rows)
  end subroutine helmholtz_rows_create

  !> The values of the rows made by helmholtz_rows_create for another coefficient (a new dt):
  !> diagonal 1 + 2c (1/dx^2 + 1/dy^2 + 1/dz^2), neighbours -c/dx^2, -c/dy^2, -c/dz^2.
  subroutine helmholtz_rows_set_coefficient(grid, coefficient, rows)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: coefficient
    type(sparse_rows_t), intent(inout) :: rows
    real(wp) :: cx, cy, cz
    integer :: row
    cx = coefficient / grid%dx**2
    cy = coefficient / grid%dy**2
    cz = coefficient / grid%dz**2
    do row = 1, rows_local_count(rows)
      rows%values(rows%row_start(row):rows%row_start(row) + stencil_size - 1) = &
          [1.0_wp + 2.0_wp * (cx + cy + cz), -cx, -cx, -cy, -cy, -cz, -cz]
    end do
  end subroutine helmholtz_rows_set_coefficient

  !> The interior of a field (0:nx+1, 0:ny+1, 0:nz_local+1) as this rank's entries in row order.
  subroutine field_to_rows(grid, field, values)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: field(0:, 0:, 0:)
    real(wp), intent(out) :: values(:)
    integer :: j, k, first
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        first = grid%nx * ((j - 1) + grid%ny * (k - 1))
        values(first + 1:first + grid%nx) = field(1:grid%nx, j, k)
      end do
    end do
  end subroutine field_to_rows

  !> The reverse of field_to_rows (halos untouched).
  subroutine rows_to_field(grid, values, field)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: values(:)
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    integer :: j, k, first
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        first = grid%nx * ((j - 1) + grid%ny * (k - 1))
        field(1:grid%nx, j, k) = values(first + 1:first + grid%nx)
      end do
    end do
  end subroutine rows_to_field
end module hypre_helmholtz_rows
