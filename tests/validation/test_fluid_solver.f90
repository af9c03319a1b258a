! ranks: 2
! checks: 11
!> Validation of the fluid solver (fluid_solver, momentum_terms, initial_fields, fluid_diagnostics)
!> on 2 ranks: projection to round-off, Taylor-Green spatial and temporal order, inviscid energy
!> conservation, and the discrete energy budget dE/dt = -dissipation.
!> References: the exact Taylor-Green solution (docs/physics.md section 2, Taylor & Green 1937);
!> the scheme's design order 2 in dx and dt; energy conservation of the divergence-form MAC
!> advection (Morinishi et al. 1998), so the only energy error left is AB2's.
program test_fluid_solver
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use parallel_env, only: parallel_start, global_sum, is_root
  use random_stream, only: random_stream_t, stream_seed, stream_normal
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_advance
  use initial_fields, only: set_taylor_green, taylor_green_exact, set_random_field
  use fluid_diagnostics, only: fluid_statistics_t, compute_fluid_statistics
  use fluid_grid, only: allocate_field
  use test_framework, only: test_start, test_finish, check_below, check_above, check_close
  implicit none
  real(wp), parameter :: length = two_pi, amplitude = 1.0_wp
  real(wp) :: errors(3), order, energy_errors(3)
  character(len=16) :: scheme
  integer :: n

  call parallel_start()
  call test_start('fluid_solver')

  call test_projection()

  ! Spatial order: 16^3, 32^3, 64^3 to t = 1 with dt = 0.01 (CN: time error ~1e-8, far below).
  do n = 1, 3
    errors(n) = taylor_green_error(8 * 2**n, 0.01_wp, 100, 'crank_nicolson')
  end do
  order = log(errors(2) / errors(3)) / log(2.0_wp)
  call report_values('Taylor-Green relative rms error, 16^3, 32^3, 64^3:', errors)
  call check_above(log(errors(1) / errors(2)) / log(2.0_wp), 1.9_wp, 'taylor_green_spatial_order_16_32')
  call check_above(order, 1.9_wp, 'taylor_green_spatial_order_32_64')

  ! Temporal order on 16^3: errors against a dt/32 reference on the same grid (removes the
  ! spatial error), dt = 0.2, 0.1, 0.05 to t = 2.
  do n = 1, 2
    scheme = merge('explicit      ', 'crank_nicolson', n == 1)
    call temporal_errors(trim(scheme), errors)
    call report_values('Taylor-Green time error ('//trim(scheme)//'), dt = 0.2, 0.1, 0.05:', errors)
    call check_above(log(errors(1) / errors(2)) / log(2.0_wp), 1.9_wp, 'taylor_green_temporal_order_'// &
                     trim(scheme)//'_coarse')
    call check_above(log(errors(2) / errors(3)) / log(2.0_wp), 1.9_wp, 'taylor_green_temporal_order_'// &
                     trim(scheme)//'_fine')
  end do

  ! Inviscid random field: relative kinetic-energy change over t = 1 for dt = 0.04, 0.02, 0.01.
  do n = 1, 3
    energy_errors(n) = inviscid_energy_error(0.04_wp / 2**(n - 1))
  end do
  call report_values('inviscid relative energy change, dt = 0.04, 0.02, 0.01:', energy_errors)
  ! 0.1% over one time unit (about one large-eddy turnover L/(2 pi U)) at CFL ~ 0.05.
  call check_below(energy_errors(3), 1.0e-3_wp, 'inviscid_energy_conserved_small_dt')
  call check_above(log(energy_errors(1) / energy_errors(2)) / log(2.0_wp), 1.9_wp, 'inviscid_energy_error_order_coarse')
  call check_above(log(energy_errors(2) / energy_errors(3)) / log(2.0_wp), 1.9_wp, 'inviscid_energy_error_order_fine')

  call test_energy_budget()
  call test_finish()

contains

  subroutine report_values(label, values)
    character(len=*), intent(in) :: label
    real(wp), intent(in) :: values(:)
    if (is_root()) write(*, '(a,3es11.3)') '  '//label, values
  end subroutine report_values

  !> From rest, one step with a random non-solenoidal body force: u* = dt f is not solenoidal,
  !> the projected u must be, to round-off: max |div u| <= 1e-12 U / dx (docs/studies/validation.md, Fluid).
  subroutine test_projection()
    type(fluid_solver_t) :: solver
    type(fluid_statistics_t) :: stats
    real(wp), allocatable :: fu(:, :, :), fv(:, :, :), fw(:, :, :)
    type(random_stream_t) :: stream
    integer :: i, j, k
    call fluid_solver_create(solver, grid_config_t(nx=32, ny=16, nz=8, length_x=1.0_wp, length_y=0.5_wp, length_z=0.25_wp), &
                             fluid_config_t(viscosity=1.0e-6_wp, density=1000.0_wp, viscous_scheme='explicit', &
                             fft_planning='estimate'))
    call allocate_field(solver%grid, fu); call allocate_field(solver%grid, fv); call allocate_field(solver%grid, fw)
    call stream_seed(stream, 5_i8)
    do k = 1, solver%grid%nz_local
      do j = 1, solver%grid%ny
        do i = 1, solver%grid%nx
          fu(i, j, k) = stream_normal(stream); fv(i, j, k) = stream_normal(stream); fw(i, j, k) = stream_normal(stream)
        end do
      end do
    end do
    call fluid_advance(solver, 1.0e-3_wp, fu, fv, fw)
    call compute_fluid_statistics(solver, 1.0e-3_wp, stats)
    call check_below(stats%max_divergence * solver%grid%dx / maxval(stats%max_speed), 1.0e-12_wp, &
                     'projection_max_divergence_relative_to_U_over_dx')
  end subroutine test_projection

  !> Relative rms error of (u, v) against the exact Taylor-Green vortex (nu = 0.1, U = 1, L = 2 pi).
  real(wp) function taylor_green_error(cells, dt, steps, viscous_scheme) result(error)
    integer, intent(in) :: cells, steps
    real(wp), intent(in) :: dt
    character(len=*), intent(in) :: viscous_scheme
    type(fluid_solver_t) :: solver
    real(wp), allocatable :: ue(:, :, :), ve(:, :, :), we(:, :, :), pe(:, :, :)
    integer :: s
    call run_taylor_green(solver, cells, dt, steps, viscous_scheme)
    call allocate_field(solver%grid, ue); call allocate_field(solver%grid, ve)
    call allocate_field(solver%grid, we); call allocate_field(solver%grid, pe)
    call taylor_green_exact(solver%grid, amplitude, solver%viscosity, 1.0_wp, steps * dt, ue, ve, we, pe)
    s = solver%grid%nz_local
    error = sqrt(global_sum(sum((solver%u(1:cells, 1:cells, 1:s) - ue(1:cells, 1:cells, 1:s))**2) &
                          + sum((solver%v(1:cells, 1:cells, 1:s) - ve(1:cells, 1:cells, 1:s))**2)) &
               / global_sum(sum(ue(1:cells, 1:cells, 1:s)**2) + sum(ve(1:cells, 1:cells, 1:s)**2)))
  end function taylor_green_error

  subroutine run_taylor_green(solver, cells, dt, steps, viscous_scheme)
    type(fluid_solver_t), intent(inout) :: solver
    integer, intent(in) :: cells, steps
    real(wp), intent(in) :: dt
    character(len=*), intent(in) :: viscous_scheme
    integer :: s
    call fluid_solver_create(solver, grid_config_t(nx=cells, ny=cells, nz=cells, length_x=length, length_y=length, &
                             length_z=length), &
                             fluid_config_t(viscosity=0.1_wp, density=1.0_wp, viscous_scheme=viscous_scheme, &
                             fft_planning='estimate'))
    call set_taylor_green(solver, amplitude)
    do s = 1, steps
      call fluid_advance(solver, dt)
    end do
  end subroutine run_taylor_green

  !> Velocity differences (relative rms) at t = 2 on 16^3 for dt = 0.2, 0.1, 0.05 against dt = 0.2/32.
  subroutine temporal_errors(viscous_scheme, errors)
    character(len=*), intent(in) :: viscous_scheme
    real(wp), intent(out) :: errors(3)
    type(fluid_solver_t) :: reference, coarse
    integer :: m
    call run_taylor_green(reference, 16, 0.2_wp / 32, 320, viscous_scheme)
    do m = 1, 3
      call run_taylor_green(coarse, 16, 0.2_wp / 2**(m - 1), 10 * 2**(m - 1), viscous_scheme)
      errors(m) = sqrt(global_sum(sum((coarse%u(1:16, 1:16, :) - reference%u(1:16, 1:16, :))**2 &
                                    + (coarse%v(1:16, 1:16, :) - reference%v(1:16, 1:16, :))**2)) &
                     / global_sum(sum(reference%u(1:16, 1:16, :)**2 + reference%v(1:16, 1:16, :)**2)))
    end do
  end subroutine temporal_errors

  !> |E(1) - E(0)| / E(0) for an inviscid random field (16^3, peak at k = 2, rms 1, so CFL ~ 0.2 at dt = 0.04).
  real(wp) function inviscid_energy_error(dt) result(error)
    real(wp), intent(in) :: dt
    type(fluid_solver_t) :: solver
    type(fluid_statistics_t) :: start, finish
    integer :: s
    call fluid_solver_create(solver, grid_config_t(nx=16, ny=16, nz=16, length_x=length, length_y=length, length_z=length), &
                             fluid_config_t(viscosity=0.0_wp, density=1.0_wp, viscous_scheme='explicit', &
                             fft_planning='estimate'))
    call set_random_field(solver, 3_i8, amplitude, 2.0_wp)
    call compute_fluid_statistics(solver, dt, start)
    do s = 1, nint(1.0_wp / dt)
      call fluid_advance(solver, dt)
    end do
    call compute_fluid_statistics(solver, dt, finish)
    error = abs(finish%kinetic_energy - start%kinetic_energy) / start%kinetic_energy
  end function inviscid_energy_error

  !> Viscous random field: the energy lost over a step equals dt times the mean of the
  !> dissipation at its ends (trapezoidal rule, CN) to O(dt^2) relative: checks that the
  !> reported dissipation is the one the scheme actually applies.
  subroutine test_energy_budget()
    type(fluid_solver_t) :: solver
    type(fluid_statistics_t) :: before, after
    real(wp), parameter :: dt = 1.0e-3_wp
    integer :: s
    call fluid_solver_create(solver, grid_config_t(nx=16, ny=16, nz=16, length_x=length, length_y=length, length_z=length), &
                             fluid_config_t(viscosity=0.05_wp, density=1.0_wp, viscous_scheme='crank_nicolson', &
                             fft_planning='estimate'))
    call set_random_field(solver, 4_i8, amplitude, 2.0_wp)
    do s = 1, 5
      call fluid_advance(solver, dt)
    end do
    call compute_fluid_statistics(solver, dt, before)
    call fluid_advance(solver, dt)
    call compute_fluid_statistics(solver, dt, after)
    call check_close((before%kinetic_energy - after%kinetic_energy) / dt, &
                     0.5_wp * (before%dissipation + after%dissipation), 1.0e-4_wp, 'energy_budget_dEdt_equals_dissipation')
  end subroutine test_energy_budget
end program test_fluid_solver
