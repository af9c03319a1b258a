!> One restart cycle of GMRES (Saad & Schultz 1986, SIAM J. Sci. Stat. Comput. 7, 856), flexible
!> when the caller keeps the preconditioned vectors (FGMRES, Saad 1993, SIAM J. Sci. Comput. 14,
!> 461): the Arnoldi basis, the Hessenberg matrix reduced by Givens rotations as it grows, and the
!> least-squares coefficients at the end. The caller applies its operator (and preconditioner) to
!> basis(:, j) and writes the product into basis(:, j + 1); gmres_orthogonalise does the rest.
!> Distributed vectors (collective = .true.) reduce their inner products over all ranks; rank-local
!> ones (a block preconditioner's) do not.
module gmres_cycle
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  implicit none
  private
  public :: gmres_cycle_t, gmres_prepare, gmres_begin, gmres_orthogonalise, gmres_coefficients

  type :: gmres_cycle_t
    real(wp), allocatable :: basis(:, :)        !< (n, restart + 1) Krylov basis
    real(wp), allocatable :: hessenberg(:, :)   !< (restart + 1, restart), upper triangle after the rotations
    real(wp), allocatable :: cosines(:), sines(:), projected(:)
    logical :: collective = .true.              !< reduce the inner products over all ranks
  end type gmres_cycle_t

contains

  !> Storage for vectors of n entries and cycles of up to `restart` columns (kept when the sizes hold).
  subroutine gmres_prepare(self, n, restart, collective)
    type(gmres_cycle_t), intent(inout) :: self
    integer, intent(in) :: n, restart
    logical, intent(in) :: collective
    self%collective = collective
    if (allocated(self%basis)) then
      if (any(shape(self%basis) /= [n, restart + 1])) deallocate(self%basis, self%hessenberg, self%cosines, &
                                                                 self%sines, self%projected)
    end if
    if (.not. allocated(self%basis)) allocate(self%basis(n, restart + 1), self%hessenberg(restart + 1, restart), &
                                              self%cosines(restart), self%sines(restart), self%projected(restart + 1))
  end subroutine gmres_prepare

  !> The first basis vector from the residual r of the cycle's starting point (norm its 2-norm, > 0).
  subroutine gmres_begin(self, residual, norm)
    type(gmres_cycle_t), intent(inout) :: self
    real(wp), intent(in) :: residual(:), norm
    self%basis(:, 1) = residual / norm
    self%projected = 0
    self%projected(1) = norm
  end subroutine gmres_begin

  !> Column j: basis(:, j + 1) holds the operator applied to (the preconditioned) basis(:, j).
  !> Orthogonalise it against the basis, apply the earlier rotations and its own; estimate is the
  !> least-squares residual norm after j columns. breakdown: the Krylov space is invariant (the new
  !> column adds nothing); the caller solves with the first j - 1 columns.
  subroutine gmres_orthogonalise(self, j, estimate, breakdown)
    type(gmres_cycle_t), intent(inout) :: self
    integer, intent(in) :: j
    real(wp), intent(out) :: estimate
    logical, intent(out) :: breakdown
    real(wp) :: coefficients(j + 1), temp
    integer :: i, pass
    ! Classical Gram-Schmidt twice: one reduction of j inner products per pass. The second pass's
    ! reduction carries the squared norm before it: its coefficients are of rounding size, so the
    ! norm after it follows without cancellation (Pythagoras).
    self%hessenberg(:, j) = 0
    do pass = 1, 2
      coefficients(1:j) = matmul(self%basis(:, j + 1), self%basis(:, 1:j))
      coefficients(j + 1) = 0
      if (pass == 2) coefficients(j + 1) = sum(self%basis(:, j + 1)**2)
      if (self%collective) call MPI_Allreduce(MPI_IN_PLACE, coefficients, j + 1, mpi_wp, MPI_SUM, world)
      self%basis(:, j + 1) = self%basis(:, j + 1) - matmul(self%basis(:, 1:j), coefficients(1:j))
      self%hessenberg(1:j, j) = self%hessenberg(1:j, j) + coefficients(1:j)
    end do
    self%hessenberg(j + 1, j) = sqrt(max(coefficients(j + 1) - sum(coefficients(1:j)**2), 0.0_wp))
    if (self%hessenberg(j + 1, j) > 0.0_wp) self%basis(:, j + 1) = self%basis(:, j + 1) / self%hessenberg(j + 1, j)
    ! The earlier Givens rotations on the new column, then its own (the least-squares residual).
    do i = 1, j - 1
      temp = self%cosines(i) * self%hessenberg(i, j) + self%sines(i) * self%hessenberg(i + 1, j)
      self%hessenberg(i + 1, j) = -self%sines(i) * self%hessenberg(i, j) + self%cosines(i) * self%hessenberg(i + 1, j)
      self%hessenberg(i, j) = temp
    end do
    temp = hypot(self%hessenberg(j, j), self%hessenberg(j + 1, j))
    breakdown = .not. (temp > 0.0_wp)
    if (breakdown) then
      estimate = abs(self%projected(j))
      return
    end if
    self%cosines(j) = self%hessenberg(j, j) / temp
    self%sines(j) = self%hessenberg(j + 1, j) / temp
    self%hessenberg(j, j) = temp
    self%hessenberg(j + 1, j) = 0
    self%projected(j + 1) = -self%sines(j) * self%projected(j)
    self%projected(j) = self%cosines(j) * self%projected(j)
    estimate = abs(self%projected(j + 1))
  end subroutine gmres_orthogonalise

  !> The coefficients y of the first j columns that minimise the residual (back substitution).
  subroutine gmres_coefficients(self, j, y)
    type(gmres_cycle_t), intent(in) :: self
    integer, intent(in) :: j
    real(wp), intent(out) :: y(:)
    integer :: i
    do i = j, 1, -1
      y(i) = (self%projected(i) - dot_product(self%hessenberg(i, i + 1:j), y(i + 1:j))) / self%hessenberg(i, i)
    end do
  end subroutine gmres_coefficients
end module gmres_cycle
