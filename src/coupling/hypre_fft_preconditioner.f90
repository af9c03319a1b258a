!> The FFT Helmholtz solve as a hypre preconditioner: M^{-1} = (I - c L_h)^{-1} on the periodic
!> box, exact for the Crank-Nicolson rows of hypre_helmholtz_rows (poisson_fft's helmholtz_solve
!> divides each Fourier mode by 1 + c times the modified wavenumber squared of the same 7-point
!> stencil). With immersed-boundary ghost rows in the system it is the inverse of the operator
!> everywhere but in those rows (docs/theory.md, "Linear solver (hypre)").
!>
!> Applied in place: the residual's rows go straight into the FFT's own buffer and the solution
!> straight from it into hypre's correction vector (the rows of a slab are its x-lines in (j, k)
!> order, the buffer's layout without the padding), two passes over the data against four with a
!> field in between; the same arithmetic, so the same bits.
module hypre_fft_preconditioner
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t
  use poisson_fft, only: poisson_fft_t, helmholtz_solve_in_buffer
  use timer_registry, only: timer_register, timer_tic, timer_toc
  use hypre_solver, only: user_preconditioner_t
  implicit none
  private
  public :: fft_helmholtz_preconditioner_t, fft_preconditioner_create

  type, extends(user_preconditioner_t) :: fft_helmholtz_preconditioner_t
    type(fluid_grid_t), pointer :: grid => null()
    type(poisson_fft_t), pointer :: fft => null()
    real(wp) :: coefficient = 0                    !< c = nu dt / 2
    integer :: timer = 0                           !< 'FFT preconditioner' (timer_registry)
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
    preconditioner%timer = timer_register('  FFT preconditioner')
  end subroutine fft_preconditioner_create

  subroutine apply_fft_helmholtz(self, residual, correction)
    class(fft_helmholtz_preconditioner_t), intent(inout) :: self
    real(wp), intent(in) :: residual(:)
    real(wp), intent(out) :: correction(:)
    integer :: j, k, first, nx
    call timer_tic(self%timer)
    nx = self%grid%nx
    associate (fft => self%fft)
      do k = 1, self%grid%nz_local
        do j = 1, self%grid%ny
          first = nx * ((j - 1) + self%grid%ny * (k - 1))
          fft%real_view(1:nx, j, k) = residual(first + 1:first + nx)
        end do
      end do
      call helmholtz_solve_in_buffer(fft, self%coefficient)
      do k = 1, self%grid%nz_local
        do j = 1, self%grid%ny
          first = nx * ((j - 1) + self%grid%ny * (k - 1))
          correction(first + 1:first + nx) = fft%real_view(1:nx, j, k) * fft%normalisation
        end do
      end do
    end associate
    if (allocated(self%replaced_rows)) correction(self%replaced_rows) = residual(self%replaced_rows) / self%replaced_diagonal
    call timer_toc(self%timer)
  end subroutine apply_fft_helmholtz
end module hypre_fft_preconditioner
