!> Spatial operators of the MAC grid (second order, periodic; fields carry one halo layer whose
!> values must be current): advection in divergence form, the 7-point Laplacian, divergence and
!> the pressure-gradient correction.
!>
!> Advection uses the divergence form with arithmetic-mean interpolation of Harlow & Welch (1965),
!> which on a uniform staggered grid conserves momentum and, for a discretely solenoidal velocity,
!> kinetic energy (Morinishi, Lund, Vasilyev & Moin 1998, J. Comput. Phys. 143, "Div." scheme).
!> For the u component at face (i,j,k) (x = i dx):
!>   N_u = [ (u_{i+1}+u_i)^2 - (u_i+u_{i-1})^2 ] / (4 dx)
!>       + [ (v_{i,j}+v_{i+1,j})(u_{j}+u_{j+1}) - (v_{i,j-1}+v_{i+1,j-1})(u_{j-1}+u_{j}) ] / (4 dy)
!>       + [ (w_{i,k}+w_{i+1,k})(u_{k}+u_{k+1}) - (w_{i,k-1}+w_{i+1,k-1})(u_{k-1}+u_{k}) ] / (4 dz)
!> and the same by cyclic permutation for v and w.
module momentum_terms
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t
  implicit none
  private
  public :: explicit_terms, laplacian, divergence, subtract_gradient

contains

  !> r = -N(u) + viscosity L(u) for all three components (interiors). viscosity = 0 gives advection only.
  subroutine explicit_terms(grid, u, v, w, viscosity, ru, rv, rw)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in), contiguous :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: viscosity
    real(wp), intent(inout), contiguous :: ru(0:, 0:, 0:), rv(0:, 0:, 0:), rw(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: qx, qy, qz, cx, cy, cz, adv
    qx = 0.25_wp / grid%dx; qy = 0.25_wp / grid%dy; qz = 0.25_wp / grid%dz
    cx = viscosity / grid%dx**2; cy = viscosity / grid%dy**2; cz = viscosity / grid%dz**2
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          adv = qx * ((u(i + 1, j, k) + u(i, j, k))**2 - (u(i, j, k) + u(i - 1, j, k))**2) &
              + qy * ((v(i, j, k) + v(i + 1, j, k)) * (u(i, j, k) + u(i, j + 1, k)) &
                    - (v(i, j - 1, k) + v(i + 1, j - 1, k)) * (u(i, j - 1, k) + u(i, j, k))) &
              + qz * ((w(i, j, k) + w(i + 1, j, k)) * (u(i, j, k) + u(i, j, k + 1)) &
                    - (w(i, j, k - 1) + w(i + 1, j, k - 1)) * (u(i, j, k - 1) + u(i, j, k)))
          ru(i, j, k) = -adv + cx * (u(i + 1, j, k) - 2 * u(i, j, k) + u(i - 1, j, k)) &
                             + cy * (u(i, j + 1, k) - 2 * u(i, j, k) + u(i, j - 1, k)) &
                             + cz * (u(i, j, k + 1) - 2 * u(i, j, k) + u(i, j, k - 1))
        end do
      end do
    end do
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          adv = qx * ((u(i, j, k) + u(i, j + 1, k)) * (v(i, j, k) + v(i + 1, j, k)) &
                    - (u(i - 1, j, k) + u(i - 1, j + 1, k)) * (v(i - 1, j, k) + v(i, j, k))) &
              + qy * ((v(i, j + 1, k) + v(i, j, k))**2 - (v(i, j, k) + v(i, j - 1, k))**2) &
              + qz * ((w(i, j, k) + w(i, j + 1, k)) * (v(i, j, k) + v(i, j, k + 1)) &
                    - (w(i, j, k - 1) + w(i, j + 1, k - 1)) * (v(i, j, k - 1) + v(i, j, k)))
          rv(i, j, k) = -adv + cx * (v(i + 1, j, k) - 2 * v(i, j, k) + v(i - 1, j, k)) &
                             + cy * (v(i, j + 1, k) - 2 * v(i, j, k) + v(i, j - 1, k)) &
                             + cz * (v(i, j, k + 1) - 2 * v(i, j, k) + v(i, j, k - 1))
        end do
      end do
    end do
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          adv = qx * ((u(i, j, k) + u(i, j, k + 1)) * (w(i, j, k) + w(i + 1, j, k)) &
                    - (u(i - 1, j, k) + u(i - 1, j, k + 1)) * (w(i - 1, j, k) + w(i, j, k))) &
              + qy * ((v(i, j, k) + v(i, j, k + 1)) * (w(i, j, k) + w(i, j + 1, k)) &
                    - (v(i, j - 1, k) + v(i, j - 1, k + 1)) * (w(i, j - 1, k) + w(i, j, k))) &
              + qz * ((w(i, j, k + 1) + w(i, j, k))**2 - (w(i, j, k) + w(i, j, k - 1))**2)
          rw(i, j, k) = -adv + cx * (w(i + 1, j, k) - 2 * w(i, j, k) + w(i - 1, j, k)) &
                             + cy * (w(i, j + 1, k) - 2 * w(i, j, k) + w(i, j - 1, k)) &
                             + cz * (w(i, j, k + 1) - 2 * w(i, j, k) + w(i, j, k - 1))
        end do
      end do
    end do
  end subroutine explicit_terms

  !> lf = L f, the 7-point Laplacian (interior).
  subroutine laplacian(grid, f, lf)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in), contiguous :: f(0:, 0:, 0:)
    real(wp), intent(inout), contiguous :: lf(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: cx, cy, cz
    cx = 1.0_wp / grid%dx**2; cy = 1.0_wp / grid%dy**2; cz = 1.0_wp / grid%dz**2
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          lf(i, j, k) = cx * (f(i + 1, j, k) - 2 * f(i, j, k) + f(i - 1, j, k)) &
                      + cy * (f(i, j + 1, k) - 2 * f(i, j, k) + f(i, j - 1, k)) &
                      + cz * (f(i, j, k + 1) - 2 * f(i, j, k) + f(i, j, k - 1))
        end do
      end do
    end do
  end subroutine laplacian

  !> div = scale * (discrete divergence of (u,v,w)) at the cell centres (interior).
  subroutine divergence(grid, u, v, w, scale, div)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in), contiguous :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: scale
    real(wp), intent(inout), contiguous :: div(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: cx, cy, cz
    cx = scale / grid%dx; cy = scale / grid%dy; cz = scale / grid%dz
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          div(i, j, k) = cx * (u(i, j, k) - u(i - 1, j, k)) + cy * (v(i, j, k) - v(i, j - 1, k)) &
                       + cz * (w(i, j, k) - w(i, j, k - 1))
        end do
      end do
    end do
  end subroutine divergence

  !> (u,v,w) -= factor * grad phi on the faces (interior); phi's halos must be current.
  subroutine subtract_gradient(grid, phi, factor, u, v, w)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in), contiguous :: phi(0:, 0:, 0:)
    real(wp), intent(in) :: factor
    real(wp), intent(inout), contiguous :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    integer :: i, j, k
    real(wp) :: cx, cy, cz
    cx = factor / grid%dx; cy = factor / grid%dy; cz = factor / grid%dz
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          u(i, j, k) = u(i, j, k) - cx * (phi(i + 1, j, k) - phi(i, j, k))
          v(i, j, k) = v(i, j, k) - cy * (phi(i, j + 1, k) - phi(i, j, k))
          w(i, j, k) = w(i, j, k) - cz * (phi(i, j, k + 1) - phi(i, j, k))
        end do
      end do
    end do
  end subroutine subtract_gradient
end module momentum_terms
