! ranks: 2
! checks: 34
!> The staged fluid step on two ranks (checks in fluid_stage_checks), and the Taylor-Green orders
!> of the incremental pressure scheme run through the staged step (test_fluid_solver has them for
!> the default scheme and the fused step).
!> References: the exact Taylor-Green solution (docs/physics.md section 2, Taylor & Green 1937);
!> the design order 2 in dx and dt of the AB2/CN scheme with the incremental pressure update
!> p^{n+1/2} = p^{n-1/2} + rho (phi - nu dt/2 L phi) (Brown, Cortez & Minion 2001, J. Comput. Phys.
!> 168, 464: second order for the velocity and the pressure).
program test_fluid_stages_two_ranks
  use agglo_kinds, only: wp
  use physical_constants, only: two_pi
  use parallel_env, only: parallel_start, global_sum, is_root
  use fluid_grid, only: allocate_field
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_predict, &
                          fluid_project, fluid_finish_step
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use initial_fields, only: set_taylor_green, taylor_green_exact
  use fluid_stage_checks, only: run_fluid_stage_checks
  use test_framework, only: test_start, test_finish, check_above
  implicit none
  real(wp), parameter :: length = two_pi, amplitude = 1.0_wp
  real(wp) :: velocity_errors(3), pressure_errors(3), errors(3)
  character(len=16) :: scheme
  integer :: n

  call parallel_start()
  call test_start('fluid_stages_two_ranks')
  call run_fluid_stage_checks('_2_ranks')

  ! Spatial order: 16^3, 32^3, 64^3 to t = 1 with dt = 0.01, Crank-Nicolson (time error far below).
  do n = 1, 3
    call taylor_green_errors(8 * 2**n, 0.01_wp, 100, velocity_errors(n), pressure_errors(n))
  end do
  call report_values('incremental: Taylor-Green velocity error, 16^3, 32^3, 64^3:', velocity_errors)
  call report_values('incremental: Taylor-Green pressure error, 16^3, 32^3, 64^3:', pressure_errors)
  call check_above(order(velocity_errors(1:2)), 1.9_wp, 'incremental_taylor_green_spatial_order_16_32')
  call check_above(order(velocity_errors(2:3)), 1.9_wp, 'incremental_taylor_green_spatial_order_32_64')
  call check_above(order(pressure_errors(1:2)), 1.9_wp, 'incremental_taylor_green_pressure_spatial_order_16_32')
  call check_above(order(pressure_errors(2:3)), 1.9_wp, 'incremental_taylor_green_pressure_spatial_order_32_64')

  ! Temporal order on 16^3: against a dt/32 reference on the same grid, dt = 0.2, 0.1, 0.05 to t = 2.
  do n = 1, 2
    scheme = merge('explicit      ', 'crank_nicolson', n == 1)
    call temporal_errors(trim(scheme), errors)
    call report_values('incremental: Taylor-Green time error ('//trim(scheme)//'), dt = 0.2, 0.1, 0.05:', errors)
    call check_above(order(errors(1:2)), 1.9_wp, 'incremental_taylor_green_temporal_order_'//trim(scheme)//'_coarse')
    call check_above(order(errors(2:3)), 1.9_wp, 'incremental_taylor_green_temporal_order_'//trim(scheme)//'_fine')
  end do
  call test_finish()

contains

  !> Observed order between two errors at a refinement ratio of 2.
  real(wp) function order(pair)
    real(wp), intent(in) :: pair(2)
    order = log(pair(1) / pair(2)) / log(2.0_wp)
  end function order

  subroutine report_values(label, values)
    character(len=*), intent(in) :: label
    real(wp), intent(in) :: values(:)
    if (is_root()) write(*, '(a,3es11.3)') '  '//label, values
  end subroutine report_values

  !> Taylor-Green (nu = 0.1, U = 1, L = 2 pi) from its exact state at t = 0 (the pressure taken as
  !> p^{-1/2}), steps of the staged step with the incremental scheme.
  subroutine run_taylor_green(solver, cells, dt, steps, viscous_scheme)
    type(fluid_solver_t), intent(inout) :: solver
    integer, intent(in) :: cells, steps
    real(wp), intent(in) :: dt
    character(len=*), intent(in) :: viscous_scheme
    integer :: s
    call fluid_solver_create(solver, grid_config_t(nx=cells, ny=cells, nz=cells, length_x=length, length_y=length, &
                                                   length_z=length), &
                             fluid_config_t(viscosity=0.1_wp, density=1.0_wp, viscous_scheme=viscous_scheme, &
                                            fft_planning='estimate', pressure_scheme='incremental'))
    call set_taylor_green(solver, amplitude)
    do s = 1, steps
      call fluid_predict(solver, dt)
      call fluid_project(solver)
      call fluid_finish_step(solver)
    end do
  end subroutine run_taylor_green

  !> Relative rms errors of (u, v) at t = steps dt and of the pressure at t - dt/2 (p^{n+1/2}).
  subroutine taylor_green_errors(cells, dt, steps, velocity_error, pressure_error)
    integer, intent(in) :: cells, steps
    real(wp), intent(in) :: dt
    real(wp), intent(out) :: velocity_error, pressure_error
    type(fluid_solver_t) :: solver
    real(wp), allocatable :: ue(:, :, :), ve(:, :, :), we(:, :, :), pe(:, :, :)
    integer :: s
    call run_taylor_green(solver, cells, dt, steps, 'crank_nicolson')
    call allocate_field(solver%grid, ue); call allocate_field(solver%grid, ve)
    call allocate_field(solver%grid, we); call allocate_field(solver%grid, pe)
    call taylor_green_exact(solver%grid, amplitude, solver%viscosity, 1.0_wp, steps * dt, ue, ve, we, pe)
    s = solver%grid%nz_local
    velocity_error = sqrt(global_sum(sum((solver%u(1:cells, 1:cells, 1:s) - ue(1:cells, 1:cells, 1:s))**2) &
                                   + sum((solver%v(1:cells, 1:cells, 1:s) - ve(1:cells, 1:cells, 1:s))**2)) &
                        / global_sum(sum(ue(1:cells, 1:cells, 1:s)**2) + sum(ve(1:cells, 1:cells, 1:s)**2)))
    call taylor_green_exact(solver%grid, amplitude, solver%viscosity, 1.0_wp, (steps - 0.5_wp) * dt, ue, ve, we, pe)
    pressure_error = sqrt(global_sum(sum((solver%pressure(1:cells, 1:cells, 1:s) - pe(1:cells, 1:cells, 1:s))**2)) &
                        / global_sum(sum(pe(1:cells, 1:cells, 1:s)**2)))
  end subroutine taylor_green_errors

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
end program test_fluid_stages_two_ranks
