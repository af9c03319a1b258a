!> Flow diagnostics of the periodic box (collective): kinetic energy, dissipation, maximum
!> divergence, CFL number, and the finiteness check the time loop relies on.
!> Definitions (volume averages over the box, per unit mass):
!>   kinetic_energy = 1/2 <u^2 + v^2 + w^2>     (each component on its own faces)
!>   dissipation    = nu < sum over components and directions of (forward difference / h)^2 >
!> With these, the semi-discrete solver satisfies d(kinetic_energy)/dt = -dissipation exactly
!> (advection and pressure do no work on a discretely solenoidal field; summation by parts of L).
!>   cfl = dt (max|u|/dx + max|v|/dy + max|w|/dz)
module fluid_diagnostics
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_MAX
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  use fluid_solver, only: fluid_solver_t
  implicit none
  private
  public :: fluid_statistics_t, compute_fluid_statistics, advective_rate

  type :: fluid_statistics_t
    real(wp) :: kinetic_energy = 0      !< m^2/s^2
    real(wp) :: dissipation = 0         !< m^2/s^3
    real(wp) :: max_divergence = 0      !< 1/s
    real(wp) :: max_speed(3) = 0        !< m/s, max |u|, |v|, |w|
    real(wp) :: cfl = 0                 !< with the dt passed in
  end type fluid_statistics_t

contains

  !> max|u|/dx + max|v|/dy + max|w|/dz (1/s) and whether the velocity is finite: the cheap
  !> per-step check (one pass, one reduction).
  subroutine advective_rate(solver, rate, finite)
    type(fluid_solver_t), intent(in) :: solver
    real(wp), intent(out) :: rate
    logical, intent(out) :: finite
    real(wp) :: maxima(4), total
    integer :: i, j, k
    maxima = 0; total = 0
    associate (u => solver%u, v => solver%v, w => solver%w)
      do k = 1, solver%grid%nz_local
        do j = 1, solver%grid%ny
          do i = 1, solver%grid%nx
            maxima(1) = max(maxima(1), abs(u(i, j, k)))
            maxima(2) = max(maxima(2), abs(v(i, j, k)))
            maxima(3) = max(maxima(3), abs(w(i, j, k)))
            total = total + u(i, j, k) + v(i, j, k) + w(i, j, k)
          end do
        end do
      end do
    end associate
    ! A NaN survives a sum but not necessarily max: flag it (and an infinity) through the sum.
    maxima(4) = merge(0.0_wp, 1.0_wp, (total == total) .and. abs(total) <= huge(total))
    call MPI_Allreduce(MPI_IN_PLACE, maxima, 4, mpi_wp, MPI_MAX, world)
    rate = maxima(1) / solver%grid%dx + maxima(2) / solver%grid%dy + maxima(3) / solver%grid%dz
    finite = maxima(4) == 0.0_wp .and. rate <= huge(rate)
  end subroutine advective_rate

  !> All diagnostics of the current state (velocity halos must be current).
  subroutine compute_fluid_statistics(solver, dt, stats)
    type(fluid_solver_t), intent(in) :: solver
    real(wp), intent(in) :: dt
    type(fluid_statistics_t), intent(out) :: stats
    real(wp) :: sums(2), maxima(4), hx, hy, hz, gradient_squared, div
    integer :: i, j, k
    associate(grid => solver%grid, u => solver%u, v => solver%v, w => solver%w)
      hx = 1.0_wp / grid%dx**2; hy = 1.0_wp / grid%dy**2; hz = 1.0_wp / grid%dz**2
      sums = 0; maxima = 0
      do k = 1, grid%nz_local
        do j = 1, grid%ny
          do i = 1, grid%nx
            sums(1) = sums(1) + u(i, j, k)**2 + v(i, j, k)**2 + w(i, j, k)**2
            gradient_squared = hx * ((u(i + 1, j, k) - u(i, j, k))**2 + (v(i + 1, j, k) - v(i, j, k))**2 &
                                     + (w(i + 1, j, k) - w(i, j, k))**2) &
                             + hy * ((u(i, j + 1, k) - u(i, j, k))**2 + (v(i, j + 1, k) - v(i, j, k))**2 &
                                     + (w(i, j + 1, k) - w(i, j, k))**2) &
                             + hz * ((u(i, j, k + 1) - u(i, j, k))**2 + (v(i, j, k + 1) - v(i, j, k))**2 &
                                     + (w(i, j, k + 1) - w(i, j, k))**2)
            sums(2) = sums(2) + gradient_squared
            div = (u(i, j, k) - u(i - 1, j, k)) / grid%dx + (v(i, j, k) - v(i, j - 1, k)) / grid%dy &
                + (w(i, j, k) - w(i, j, k - 1)) / grid%dz
            maxima(1) = max(maxima(1), abs(div))
            maxima(2) = max(maxima(2), abs(u(i, j, k)))
            maxima(3) = max(maxima(3), abs(v(i, j, k)))
            maxima(4) = max(maxima(4), abs(w(i, j, k)))
          end do
        end do
      end do
      call MPI_Allreduce(MPI_IN_PLACE, sums, 2, mpi_wp, MPI_SUM, world)
      call MPI_Allreduce(MPI_IN_PLACE, maxima, 4, mpi_wp, MPI_MAX, world)
      stats%kinetic_energy = 0.5_wp * sums(1) / grid%cells_total
      stats%dissipation = solver%viscosity * sums(2) / grid%cells_total
      stats%max_divergence = maxima(1)
      stats%max_speed = maxima(2:4)
      stats%cfl = dt * (maxima(2) / grid%dx + maxima(3) / grid%dy + maxima(4) / grid%dz)
    end associate
  end subroutine compute_fluid_statistics
end module fluid_diagnostics
