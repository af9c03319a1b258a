!> The FFT Helmholtz solve as a hypre preconditioner: M^{-1} = (I - c L_h)^{-1} on the periodic
!> box, exact for the Crank-Nicolson rows of hypre_helmholtz_rows (poisson_fft's helmholtz_solve
!> divides each Fourier mode by 1 + c times the modified wavenumber squared of the same 7-point
!> stencil). With immersed-boundary ghost rows in the system it is the inverse of the operator
!> everywhere but in those rows (docs/theory.md, "Linear solver (hypre)").
module hypre_fft_preconditioner
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t, allocate_field
  use poisson_fft, only: poisson_fft_t, helmholtz_solve
  use hypre_solver, only: user_preconditioner_t
  use hypre_helmholtz_rows, only: field_to_rows, rows_to_field
  implicit none
  private
  public :: fft_helmholtz_preconditioner_t, fft_preconditioner_create

  type, extends(user_preconditioner_t) :: fft_helmholtz_preconditioner_t
    type(fluid_grid_t), pointer :: grid => null()
    type(poisson_fft_t), pointer :: fft => null()
    real(wp) :: coefficient = 0                    !< c = nu dt / 2
    real(wp), allocatable :: work(:, :, :)         !< one field, allocated once
    !> Rows the caller replaced (ghost and interior rows of bodies): their correction is the
    !> Jacobi one, residual / diagonal, instead of the FFT's (none if not allocated).
    integer, allocatable :: replaced_rows(:)       !< local row numbers
    real(wp), allocatable :: replaced_diagonal(:)  !< their diagonal entries
  contains
    procedure :: apply => apply_fft_helmholtz
  end type fft_helmholtz_preconditioner_t

contains

  !> grid and fft (already created on grid) must have the target attribute and outlive the
  !> preconditioner.
  subroutine fft_preconditioner_create(preconditioner, grid, fft, coefficient)
    type(fft_helmholtz_preconditioner_t), intent(out) :: preconditioner
    type(fluid_grid_t), intent(in), target :: grid
    type(poisson_fft_t), intent(inout), target :: fft
    real(wp), intent(in) :: coefficient
    preconditioner%grid => grid
    preconditioner%fft => fft
    preconditioner%coefficient = coefficient
    call allocate_field(grid, preconditioner%work)
  end subroutine fft_preconditioner_create

  subroutine apply_fft_helmholtz(self, residual, correction)
    class(fft_helmholtz_preconditioner_t), intent(inout) :: self
    real(wp), intent(in) :: residual(:)
    real(wp), intent(out) :: correction(:)
    call rows_to_field(self%grid, residual, self%work)
    call helmholtz_solve(self%fft, self%work, self%coefficient)
    call field_to_rows(self%grid, self%work, correction)
    if (allocated(self%replaced_rows)) correction(self%replaced_rows) = residual(self%replaced_rows) / self%replaced_diagonal
  end subroutine apply_fft_helmholtz
end module hypre_fft_preconditioner
