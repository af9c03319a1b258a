!> The linear system of the momentum predictor, and the interface of whoever solves it.
!>
!> Each velocity component of the predictor satisfies (docs/theory.md, fluid section)
!>   A u* = b,   A = I - alpha L,
!> with alpha = nu dt / 2 for Crank-Nicolson and alpha = 0 for explicit diffusion (then A = I and
!> u* = b). L is the 7-point Laplacian on the component's own staggered grid, b the right-hand side
!> the predictor sweep assembles (u^n + dt (AB2 terms + f [- G p / rho]) + alpha L u^n).
!>
!> fluid/ solves this with the FFT (A is constant-coefficient and periodic, so diagonal in Fourier
!> space): fft_predictor_solver_t, the default. A caller that needs other rows in the system (the
!> immersed boundary replaces the rows of its ghost nodes by interpolation conditions) extends
!> predictor_solver_t in its own room and passes it to fluid_predict; fluid/ never learns what the
!> extra rows are. apply_predictor_operator (A times a field) and the FFT solve
!> (helmholtz_solve of poisson_fft, exact for the periodic A) are the building blocks of such a
!> solver, e.g. a Krylov method preconditioned by the FFT solve.
module predictor_solver
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t
  use poisson_fft, only: poisson_fft_t, helmholtz_solve
  use momentum_terms, only: laplacian
  implicit none
  private
  public :: predictor_solver_t, fft_predictor_solver_t, apply_predictor_operator

  !> Solves A u* = b for the three velocity components of one step.
  type, abstract :: predictor_solver_t
  contains
    procedure(predictor_solve), deferred :: solve
  end type predictor_solver_t

  abstract interface
    !> On entry u, v, w hold b in their interiors (halos not current); on exit u* in the
    !> interiors (the caller refreshes the halos afterwards). alpha as in the module header:
    !> 0 means A = I. grid and poisson are the fluid's own: the FFT buffer may be used (it holds
    !> nothing the step still needs during this call), the halo buffers too.
    subroutine predictor_solve(self, grid, poisson, alpha, u, v, w)
      import :: predictor_solver_t, fluid_grid_t, poisson_fft_t, wp
      class(predictor_solver_t), intent(inout) :: self
      type(fluid_grid_t), intent(inout) :: grid
      type(poisson_fft_t), intent(inout) :: poisson
      real(wp), intent(in) :: alpha
      real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    end subroutine predictor_solve
  end interface

  !> The default: one FFT Helmholtz solve per component (exact for the periodic operator);
  !> nothing at all when alpha = 0 (A = I, so b is already u*, bit for bit).
  type, extends(predictor_solver_t) :: fft_predictor_solver_t
  contains
    procedure :: solve => fft_solve
  end type fft_predictor_solver_t

contains

  subroutine fft_solve(self, grid, poisson, alpha, u, v, w)
    class(fft_predictor_solver_t), intent(inout) :: self
    type(fluid_grid_t), intent(inout) :: grid
    type(poisson_fft_t), intent(inout) :: poisson
    real(wp), intent(in) :: alpha
    real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    if (alpha <= 0.0_wp) return
    call helmholtz_solve(poisson, u, alpha)
    call helmholtz_solve(poisson, v, alpha)
    call helmholtz_solve(poisson, w, alpha)
  end subroutine fft_solve

  !> result = A field = field - alpha L field (interior), for any component (L is the same
  !> stencil on every staggered grid of the periodic box). field's halos must be current.
  subroutine apply_predictor_operator(grid, alpha, field, result)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: alpha
    real(wp), intent(in), contiguous :: field(0:, 0:, 0:)
    real(wp), intent(inout), contiguous :: result(0:, 0:, 0:)
    integer :: i, j, k
    call laplacian(grid, field, result)
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          result(i, j, k) = field(i, j, k) - alpha * result(i, j, k)
        end do
      end do
    end do
  end subroutine apply_predictor_operator
end module predictor_solver
