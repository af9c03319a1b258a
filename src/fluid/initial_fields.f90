!> Initial velocity fields of the periodic box: rest, Taylor-Green, and a seeded random
!> solenoidal field (the 'file' option is read by the driver through the I/O layer).
module initial_fields
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use random_stream, only: random_stream_t, stream_seed, stream_normal
  use parallel_env, only: global_sum
  use fluid_grid, only: fluid_grid_t, allocate_field, exchange_halos, x_centre, y_centre, x_face, y_face
  use poisson_fft, only: spectral_filter, spectral_weight_t
  use fluid_solver, only: fluid_solver_t, fluid_exchange_velocity
  implicit none
  private
  public :: set_rest, set_taylor_green, taylor_green_exact, set_random_field, random_stream_id

  integer, parameter :: random_stream_id = 1     !< stream of the fluid's initial field (docs/design.md, "Conventions")
  !> The random field's filter exp(-(|k|/k_p)^2).
  type, extends(spectral_weight_t) :: gaussian_filter_t
    real(wp) :: peak = 1.0_wp                    !< 1/m, k_p
  contains
    procedure :: weight => gaussian_weight
  end type gaussian_filter_t

contains

  subroutine set_rest(solver)
    type(fluid_solver_t), intent(inout) :: solver
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
  end subroutine set_rest

  !> The 2-D Taylor-Green vortex in x-y, uniform in z, an exact Navier-Stokes solution
  !> (docs/physics.md section 2, generalised to lx /= ly with a = 2 pi / lx, b = 2 pi / ly):
  !>   u = U sin(a x) cos(b y) g,  v = -U (a/b) cos(a x) sin(b y) g,  w = 0,  g = exp(-nu (a^2 + b^2) t),
  !>   p = rho U^2 / 4 (cos 2ax + (a/b)^2 cos 2by) g^2.
  subroutine set_taylor_green(solver, amplitude)
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: amplitude
    call taylor_green_exact(solver%grid, amplitude, solver%viscosity, solver%density, 0.0_wp, &
                            solver%u, solver%v, solver%w, solver%pressure)
    call fluid_exchange_velocity(solver)
  end subroutine set_taylor_green

  !> The Taylor-Green solution at time t sampled at the MAC positions (interiors).
  subroutine taylor_green_exact(grid, amplitude, viscosity, density, time, u, v, w, pressure)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: amplitude, viscosity, density, time
    real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:), pressure(0:, 0:, 0:)
    real(wp) :: a, b, decay
    integer :: i, j, k
    a = two_pi / grid%lx; b = two_pi / grid%ly
    decay = exp(-viscosity * (a**2 + b**2) * time)
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          u(i, j, k) = amplitude * sin(a * x_face(grid, i)) * cos(b * y_centre(grid, j)) * decay
          v(i, j, k) = -amplitude * (a / b) * cos(a * x_centre(grid, i)) * sin(b * y_face(grid, j)) * decay
          w(i, j, k) = 0.0_wp
          pressure(i, j, k) = 0.25_wp * density * amplitude**2 * (cos(2 * a * x_centre(grid, i)) &
              + (a / b)**2 * cos(2 * b * y_centre(grid, j))) * decay**2
        end do
      end do
    end do
  end subroutine taylor_green_exact

  !> A random solenoidal field, the same on any number of ranks (to FFT round-off):
  !> white noise for a vector potential A on the cell edges, drawn from stream 1 in one fixed
  !> global order (plane by plane, so every rank draws the planes before its own and keeps its
  !> own), filtered by exp(-(|k|/k_p)^2), then u = curl A with the staggered differences, which
  !> is discretely divergence-free (div curl = 0 for commuting differences). The velocity energy
  !> spectrum is then E(k) ~ k^4 exp(-2 (k/k_p)^2) (peak at k_p); finally u is scaled so that
  !> the rms of one component, sqrt(<u^2+v^2+w^2>/3), equals amplitude.
  subroutine set_random_field(solver, seed, amplitude, peak_wavenumber)
    type(fluid_solver_t), intent(inout) :: solver
    integer(i8), intent(in) :: seed
    real(wp), intent(in) :: amplitude        !< m/s, rms of one velocity component
    real(wp), intent(in) :: peak_wavenumber  !< 1/m, peak of the energy spectrum
    type(random_stream_t) :: stream
    type(gaussian_filter_t) :: filter
    real(wp), allocatable :: ax(:, :, :), ay(:, :, :), az(:, :, :)
    real(wp) :: gx, gy, gz, rms, idx, idy, idz
    integer :: i, j, k, kg
    associate(grid => solver%grid)
      call allocate_field(grid, ax); call allocate_field(grid, ay); call allocate_field(grid, az)
      call stream_seed(stream, seed, random_stream_id)
      do kg = 1, grid%z_offset + grid%nz_local
        k = kg - grid%z_offset
        do j = 1, grid%ny
          do i = 1, grid%nx
            gx = stream_normal(stream); gy = stream_normal(stream); gz = stream_normal(stream)
            if (k >= 1) then
              ax(i, j, k) = gx; ay(i, j, k) = gy; az(i, j, k) = gz
            end if
          end do
        end do
      end do
      filter%peak = peak_wavenumber
      call spectral_filter(solver%poisson, ax, filter)
      call spectral_filter(solver%poisson, ay, filter)
      call spectral_filter(solver%poisson, az, filter)
      call exchange_halos(grid, ax); call exchange_halos(grid, ay); call exchange_halos(grid, az)
      idx = 1.0_wp / grid%dx; idy = 1.0_wp / grid%dy; idz = 1.0_wp / grid%dz
      do k = 1, grid%nz_local
        do j = 1, grid%ny
          do i = 1, grid%nx
            solver%u(i, j, k) = (az(i, j, k) - az(i, j - 1, k)) * idy - (ay(i, j, k) - ay(i, j, k - 1)) * idz
            solver%v(i, j, k) = (ax(i, j, k) - ax(i, j, k - 1)) * idz - (az(i, j, k) - az(i - 1, j, k)) * idx
            solver%w(i, j, k) = (ay(i, j, k) - ay(i - 1, j, k)) * idx - (ax(i, j, k) - ax(i, j - 1, k)) * idy
          end do
        end do
      end do
      rms = sqrt(global_sum(sum(solver%u(1:grid%nx, 1:grid%ny, 1:grid%nz_local)**2) &
                          + sum(solver%v(1:grid%nx, 1:grid%ny, 1:grid%nz_local)**2) &
                          + sum(solver%w(1:grid%nx, 1:grid%ny, 1:grid%nz_local)**2)) / (3.0_wp * grid%cells_total))
      if (rms > 0) then
        solver%u = solver%u * (amplitude / rms)
        solver%v = solver%v * (amplitude / rms)
        solver%w = solver%w * (amplitude / rms)
      end if
    end associate
    solver%pressure = 0
    call fluid_exchange_velocity(solver)
  end subroutine set_random_field

  pure real(wp) function gaussian_weight(self, wavenumber)
    class(gaussian_filter_t), intent(in) :: self
    real(wp), intent(in) :: wavenumber
    gaussian_weight = exp(-(wavenumber / self%peak)**2)
  end function gaussian_weight
end module initial_fields
