!> Spatial operators of the MAC grid (second order, periodic; fields carry one halo layer whose
!> values must be current): advection in divergence form and 7-point diffusion inside the AB2
!> predictor, the divergence, and the pressure-gradient correction.
!>
!> Advection uses the divergence form with arithmetic-mean interpolation of Harlow & Welch (1965),
!> which on a uniform staggered grid conserves momentum and, for a discretely solenoidal velocity,
!> kinetic energy (Morinishi, Lund, Vasilyev & Moin 1998, J. Comput. Phys. 143, "Div." scheme).
!> For the u component at face (i,j,k) (x = i dx):
!>   N_u = [ (u_{i+1}+u_i)^2 - (u_i+u_{i-1})^2 ] / (4 dx)
!>       + [ (v_{i,j}+v_{i+1,j})(u_{j}+u_{j+1}) - (v_{i,j-1}+v_{i+1,j-1})(u_{j-1}+u_{j}) ] / (4 dy)
!>       + [ (w_{i,k}+w_{i+1,k})(u_{k}+u_{k+1}) - (w_{i,k-1}+w_{i+1,k-1})(u_{k-1}+u_{k}) ] / (4 dz)
!> and the same by cyclic permutation for v and w.
!>
!> Performance layout (docs/studies/performance.md, Fluid): the operators work one z plane at a time so the
!> solver can fuse them into few sweeps over memory and overlap halo messages with interior planes.
!> predictor_plane computes all three components of -N(u) + nu L u and the AB2 predictor in one
!> k-j-i pass (u, v, w read once instead of three times); divergence_plane writes div u* straight
!> into the FFT buffer; correction_plane reads the potential straight from the FFT buffer and
!> refreshes the x-y halos of the plane it corrects. Inner loops run over i (unit stride).
module momentum_terms
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t
  implicit none
  private
  public :: predictor_coefficients_t, predictor_plane, divergence_plane, correction_plane, laplacian

  !> Coefficients of the predictor u* = u + dt (b1 E^n + b0 E^{n-1}) + implicit_weight D(u) [+ dt f]
  !> [- pressure_factor G p], E^n = -N(u) + explicit_weight D(u), D(u) = diffusion L u.
  !> Explicit viscous term: diffusion = nu, explicit_weight = 1, implicit_weight = 0;
  !> Crank-Nicolson right-hand side: diffusion = nu dt / 2, explicit_weight = 0, implicit_weight = 1.
  !> (Weights 0 and 1 are exact in floating point: both cases give the unfused formulas bit for bit.)
  type :: predictor_coefficients_t
    real(wp) :: dt = 0, b1 = 1, b0 = 0
    real(wp) :: diffusion = 0                   !< m^2/s (nu) or m^2 (nu dt / 2)
    real(wp) :: explicit_weight = 1, implicit_weight = 0
    real(wp) :: pressure_factor = 0             !< m^3 s/kg: dt / rho with the incremental pressure
  end type predictor_coefficients_t

contains

  !> Plane k of the predictor for the three components at once (interior). u, v, w with current
  !> halos; on entry star_* hold E^{n-1}, on exit u* (each point is read before it is written,
  !> so the history array doubles as the predictor's output and nothing extra is allocated);
  !> explicit_* receive E^n. Optional body force f (m/s^2) added as dt f; optional pressure p (Pa,
  !> cell centres, halos current) enters as - (dt / rho) G p (the incremental pressure scheme).
  subroutine predictor_plane(grid, k, c, u, v, w, explicit_u, explicit_v, explicit_w, star_u, star_v, star_w, &
                             force_u, force_v, force_w, pressure)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: k
    type(predictor_coefficients_t), intent(in) :: c
    real(wp), intent(in), contiguous :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(inout), contiguous :: explicit_u(0:, 0:, 0:), explicit_v(0:, 0:, 0:), explicit_w(0:, 0:, 0:)
    real(wp), intent(inout), contiguous :: star_u(0:, 0:, 0:), star_v(0:, 0:, 0:), star_w(0:, 0:, 0:)
    real(wp), intent(in), optional :: force_u(0:, 0:, 0:), force_v(0:, 0:, 0:), force_w(0:, 0:, 0:)
    real(wp), intent(in), optional :: pressure(0:, 0:, 0:)
    integer :: i, j, nx
    real(wp) :: qx, qy, qz, cx, cy, cz, adv, diff, e, px, py, pz
    nx = grid%nx
    qx = 0.25_wp / grid%dx; qy = 0.25_wp / grid%dy; qz = 0.25_wp / grid%dz
    cx = c%diffusion / grid%dx**2; cy = c%diffusion / grid%dy**2; cz = c%diffusion / grid%dz**2
    do j = 1, grid%ny
      ! u at (i dx, (j-1/2) dy, (k-1/2) dz)
      do i = 1, nx
        adv = qx * ((u(i + 1, j, k) + u(i, j, k))**2 - (u(i, j, k) + u(i - 1, j, k))**2) &
            + qy * ((v(i, j, k) + v(i + 1, j, k)) * (u(i, j, k) + u(i, j + 1, k)) &
                  - (v(i, j - 1, k) + v(i + 1, j - 1, k)) * (u(i, j - 1, k) + u(i, j, k))) &
            + qz * ((w(i, j, k) + w(i + 1, j, k)) * (u(i, j, k) + u(i, j, k + 1)) &
                  - (w(i, j, k - 1) + w(i + 1, j, k - 1)) * (u(i, j, k - 1) + u(i, j, k)))
        diff = cx * (u(i + 1, j, k) - 2 * u(i, j, k) + u(i - 1, j, k)) &
             + cy * (u(i, j + 1, k) - 2 * u(i, j, k) + u(i, j - 1, k)) &
             + cz * (u(i, j, k + 1) - 2 * u(i, j, k) + u(i, j, k - 1))
        e = -adv + c%explicit_weight * diff
        explicit_u(i, j, k) = e
        star_u(i, j, k) = u(i, j, k) + c%dt * (c%b1 * e + c%b0 * star_u(i, j, k)) + c%implicit_weight * diff
      end do
      ! v at ((i-1/2) dx, j dy, (k-1/2) dz)
      do i = 1, nx
        adv = qx * ((u(i, j, k) + u(i, j + 1, k)) * (v(i, j, k) + v(i + 1, j, k)) &
                  - (u(i - 1, j, k) + u(i - 1, j + 1, k)) * (v(i - 1, j, k) + v(i, j, k))) &
            + qy * ((v(i, j + 1, k) + v(i, j, k))**2 - (v(i, j, k) + v(i, j - 1, k))**2) &
            + qz * ((w(i, j, k) + w(i, j + 1, k)) * (v(i, j, k) + v(i, j, k + 1)) &
                  - (w(i, j, k - 1) + w(i, j + 1, k - 1)) * (v(i, j, k - 1) + v(i, j, k)))
        diff = cx * (v(i + 1, j, k) - 2 * v(i, j, k) + v(i - 1, j, k)) &
             + cy * (v(i, j + 1, k) - 2 * v(i, j, k) + v(i, j - 1, k)) &
             + cz * (v(i, j, k + 1) - 2 * v(i, j, k) + v(i, j, k - 1))
        e = -adv + c%explicit_weight * diff
        explicit_v(i, j, k) = e
        star_v(i, j, k) = v(i, j, k) + c%dt * (c%b1 * e + c%b0 * star_v(i, j, k)) + c%implicit_weight * diff
      end do
      ! w at ((i-1/2) dx, (j-1/2) dy, k dz)
      do i = 1, nx
        adv = qx * ((u(i, j, k) + u(i, j, k + 1)) * (w(i, j, k) + w(i + 1, j, k)) &
                  - (u(i - 1, j, k) + u(i - 1, j, k + 1)) * (w(i - 1, j, k) + w(i, j, k))) &
            + qy * ((v(i, j, k) + v(i, j, k + 1)) * (w(i, j, k) + w(i, j + 1, k)) &
                  - (v(i, j - 1, k) + v(i, j - 1, k + 1)) * (w(i, j - 1, k) + w(i, j, k))) &
            + qz * ((w(i, j, k + 1) + w(i, j, k))**2 - (w(i, j, k) + w(i, j, k - 1))**2)
        diff = cx * (w(i + 1, j, k) - 2 * w(i, j, k) + w(i - 1, j, k)) &
             + cy * (w(i, j + 1, k) - 2 * w(i, j, k) + w(i, j - 1, k)) &
             + cz * (w(i, j, k + 1) - 2 * w(i, j, k) + w(i, j, k - 1))
        e = -adv + c%explicit_weight * diff
        explicit_w(i, j, k) = e
        star_w(i, j, k) = w(i, j, k) + c%dt * (c%b1 * e + c%b0 * star_w(i, j, k)) + c%implicit_weight * diff
      end do
      ! The body force after the AB2 sum, as in u* = (u + dt (b1 E + b0 E_old)) + dt f.
      if (present(force_u)) then
        do i = 1, nx
          star_u(i, j, k) = star_u(i, j, k) + c%dt * force_u(i, j, k)
        end do
      end if
      if (present(force_v)) then
        do i = 1, nx
          star_v(i, j, k) = star_v(i, j, k) + c%dt * force_v(i, j, k)
        end do
      end if
      if (present(force_w)) then
        do i = 1, nx
          star_w(i, j, k) = star_w(i, j, k) + c%dt * force_w(i, j, k)
        end do
      end if
      ! The old pressure gradient last: u* = (...) + dt f - (dt / rho) G p^{n-1/2} (each component
      ! at its own face, the gradient being the centred difference of the two cells it separates).
      if (present(pressure)) then
        px = c%pressure_factor / grid%dx; py = c%pressure_factor / grid%dy; pz = c%pressure_factor / grid%dz
        do i = 1, nx
          star_u(i, j, k) = star_u(i, j, k) - px * (pressure(i + 1, j, k) - pressure(i, j, k))
          star_v(i, j, k) = star_v(i, j, k) - py * (pressure(i, j + 1, k) - pressure(i, j, k))
          star_w(i, j, k) = star_w(i, j, k) - pz * (pressure(i, j, k + 1) - pressure(i, j, k))
        end do
      end if
    end do
  end subroutine predictor_plane

  !> lf = L f, the 7-point Laplacian (interior). The step has it fused into predictor_plane; this
  !> stand-alone form is the reference operator (tests check the FFT solvers against it).
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

  !> rhs(1:nx, 1:ny, k) = scale * (discrete divergence of (u,v,w) at the cell centres of plane k).
  !> rhs is laid out like the FFT's padded real buffer (first extent >= nx, 1-based). Needs
  !> w(:, :, k-1) current; the x and y periodic images u(0, :, k) and v(:, 0, k) are refreshed
  !> here from the plane's own interior, so u and v need no halo exchange first.
  subroutine divergence_plane(grid, k, u, v, w, scale, rhs)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: k
    real(wp), intent(inout), contiguous :: u(0:, 0:, 0:), v(0:, 0:, 0:)
    real(wp), intent(in), contiguous :: w(0:, 0:, 0:)
    real(wp), intent(in) :: scale
    real(wp), intent(inout), contiguous :: rhs(:, :, :)
    integer :: i, j, nx, ny
    real(wp) :: cx, cy, cz
    nx = grid%nx; ny = grid%ny
    cx = scale / grid%dx; cy = scale / grid%dy; cz = scale / grid%dz
    do j = 1, ny
      u(0, j, k) = u(nx, j, k)
    end do
    do i = 1, nx
      v(i, 0, k) = v(i, ny, k)
    end do
    do j = 1, ny
      do i = 1, nx
        rhs(i, j, k) = cx * (u(i, j, k) - u(i - 1, j, k)) + cy * (v(i, j, k) - v(i, j - 1, k)) &
                     + cz * (w(i, j, k) - w(i, j, k - 1))
      end do
    end do
  end subroutine divergence_plane

  !> Plane k of the projection, in place: u = u* - factor grad phi on the faces (interior), then
  !> the plane's x-y halo ring from its periodic images. phi_here and phi_above are the potential
  !> on planes k and k+1 in the FFT's padded layout (first extent >= nx), with no halos: the
  !> periodic neighbours i = nx+1 -> 1 and j = ny+1 -> 1 are taken by index. In place because
  !> writing a separate output array would cost the memory traffic of reading it first.
  subroutine correction_plane(grid, k, phi_here, phi_above, factor, u, v, w)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: k
    real(wp), intent(in), contiguous :: phi_here(:, :), phi_above(:, :)
    real(wp), intent(in) :: factor
    real(wp), intent(inout), contiguous :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    integer :: i, j, j_next, nx, ny
    real(wp) :: cx, cy, cz
    nx = grid%nx; ny = grid%ny
    cx = factor / grid%dx; cy = factor / grid%dy; cz = factor / grid%dz
    do j = 1, ny
      j_next = merge(1, j + 1, j == ny)
      do i = 1, nx - 1
        u(i, j, k) = u(i, j, k) - cx * (phi_here(i + 1, j) - phi_here(i, j))
      end do
      u(nx, j, k) = u(nx, j, k) - cx * (phi_here(1, j) - phi_here(nx, j))
      do i = 1, nx
        v(i, j, k) = v(i, j, k) - cy * (phi_here(i, j_next) - phi_here(i, j))
        w(i, j, k) = w(i, j, k) - cz * (phi_above(i, j) - phi_here(i, j))
      end do
      ! Periodic x images of this row (cache-hot now; a separate pass would stride through memory).
      u(0, j, k) = u(nx, j, k); u(nx + 1, j, k) = u(1, j, k)
      v(0, j, k) = v(nx, j, k); v(nx + 1, j, k) = v(1, j, k)
      w(0, j, k) = w(nx, j, k); w(nx + 1, j, k) = w(1, j, k)
    end do
    ! Periodic y images over the full x range (fills the x-y edge halos too).
    do i = 0, nx + 1
      u(i, 0, k) = u(i, ny, k); u(i, ny + 1, k) = u(i, 1, k)
      v(i, 0, k) = v(i, ny, k); v(i, ny + 1, k) = v(i, 1, k)
      w(i, 0, k) = w(i, ny, k); w(i, ny + 1, k) = w(i, 1, k)
    end do
  end subroutine correction_plane
end module momentum_terms
