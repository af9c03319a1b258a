! checks: 2
!> Forced periodic box: the fluid solver driven by the Eswaran-Pope forcing (fluid_advance's body
!> force), checked against the energy budget and for exact continuation.
!>
!> Without arguments (the test suite):
!>  - power balance: in the statistically stationary state the mean power input <f.u> equals the
!>    mean dissipation nu <|grad u|^2> (docs/physics.md section 3: "check <f.u> against the measured
!>    dissipation"; the discrete kinetic energy obeys dk/dt = <f.u> - epsilon, flow_statistics).
!>    Tolerance 5% (docs/studies/validation.md, Forcing). The averaging window is 0.6 s = 60 T_L after a 0.15 s transient
!>    (6 viscous times 1/(nu kappa0^2) = 0.025 s of the forced scale).
!>    Printed for information: the energy change over the window (k_end - k_start)/W, which the
!>    difference <P> - <epsilon> matches only up to O(dt) terms of the scheme (AB2 viscous terms, the
!>    forward-Euler forcing's own work dt <|f|^2>/2, also printed), about 1% of epsilon here.
!>  - in-memory restart: a copy of the solver state plus the packed forcing state continues bit for bit.
!> With arguments "fields PATH": 40 forced steps from rest, the velocity written to PATH (HDF5) for
!> the 1-rank vs 2-rank comparison of tests/validation/test_forced_box_ranks.sh.
program test_forced_box
  use agglo_kinds, only: wp, i8
  use config_forcing, only: forcing_config_t
  use eswaran_pope_forcing, only: ep_forcing_t, forcing_init_on_grid, forcing_advance, forcing_set_fields, &
      forcing_power_input, forcing_pack_state, forcing_unpack_state
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_advance
  use flow_statistics, only: flow_statistics_t, compute_flow_statistics
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists, h5_finalize
  use hdf5_datasets, only: h5_write_slab
  use parallel_env, only: parallel_start, is_root, global_max
  use test_framework, only: test_start, test_finish, check, check_close
  implicit none

  integer, parameter :: n = 16
  real(wp), parameter :: length = 1.0e-3_wp, nu = 1.0e-6_wp, rho = 997.0_wp, dt = 2.5e-4_wp
  type(forcing_config_t) :: cfg
  character(len=256) :: mode, path

  call parallel_start()
  cfg%time_scale = 0.01_wp
  cfg%target_dissipation = 8.0e-3_wp      ! the paper's box, docs/physics.md section 3 (rough figure)
  mode = ''
  if (command_argument_count() >= 2) then
    call get_command_argument(1, mode)
    call get_command_argument(2, path)
  end if
  call test_start('forced_box')
  if (mode == 'fields') then
    call write_fields(trim(path))
  else
    call power_balance_and_restart()
  end if
  call h5_finalize()
  call test_finish()

contains

  subroutine setup(solver, forcing, fx, fy, fz)
    type(fluid_solver_t), intent(inout) :: solver
    type(ep_forcing_t), intent(inout) :: forcing
    real(wp), allocatable, intent(inout) :: fx(:,:,:), fy(:,:,:), fz(:,:,:)
    call fluid_solver_create(solver, grid_config_t(nx=n, ny=n, nz=n, length_x=length, length_y=length, length_z=length), &
                             fluid_config_t(viscosity=nu, density=rho, viscous_scheme='explicit', fft_planning='estimate'))
    call forcing_init_on_grid(forcing, cfg, 20250224, solver%grid)
    if (.not. allocated(fx)) allocate(fx, fy, fz, mold=solver%u)
  end subroutine setup

  !> One time step: advance the OU processes to the new time level's forcing, evaluate it on the
  !> faces and hand it to the solver (forward Euler in the predictor).
  subroutine forced_step(solver, forcing, fx, fy, fz, power, force_squared)
    type(fluid_solver_t), intent(inout) :: solver
    type(ep_forcing_t), intent(inout) :: forcing
    real(wp), intent(inout) :: fx(0:, 0:, 0:), fy(0:, 0:, 0:), fz(0:, 0:, 0:)
    real(wp), intent(out), optional :: power, force_squared
    call forcing_set_fields(forcing, fx, fy, fz)
    if (present(power)) power = forcing_power_input(forcing, solver%u, solver%v, solver%w)
    if (present(force_squared)) force_squared = forcing_power_input(forcing, fx, fy, fz)
    call fluid_advance(solver, dt, fx, fy, fz)
    call forcing_advance(forcing, dt)
  end subroutine forced_step

  subroutine power_balance_and_restart()
    type(fluid_solver_t) :: solver, copy
    type(ep_forcing_t) :: forcing, forcing_copy
    type(flow_statistics_t) :: stats
    real(wp), allocatable :: fx(:,:,:), fy(:,:,:), fz(:,:,:)
    integer(i8), allocatable :: words(:)
    integer :: step, transient_steps, window_steps, samples
    real(wp) :: power, mean_power, mean_dissipation, energy_start, energy_end, mean_u_rms, mean_re_lambda
    real(wp) :: force_squared, mean_force_squared
    logical :: same
    call setup(solver, forcing, fx, fy, fz)
    transient_steps = nint(0.15_wp / dt)
    window_steps = nint(0.6_wp / dt)
    do step = 1, transient_steps
      call forced_step(solver, forcing, fx, fy, fz)
    end do
    mean_power = 0; mean_dissipation = 0; samples = 0; mean_u_rms = 0; mean_re_lambda = 0; mean_force_squared = 0
    call compute_flow_statistics(stats, solver)
    energy_start = stats%kinetic_energy + 0.5_wp * sum(stats%mean_velocity**2)
    do step = 1, window_steps
      ! P^n = <f^n . u^n> and epsilon^n at the start of each step: the rates of the step's energy change.
      call compute_flow_statistics(stats, solver)
      call forced_step(solver, forcing, fx, fy, fz, power, force_squared)
      mean_power = mean_power + power
      mean_force_squared = mean_force_squared + force_squared
      mean_dissipation = mean_dissipation + stats%dissipation
      mean_u_rms = mean_u_rms + stats%u_rms
      mean_re_lambda = mean_re_lambda + stats%re_lambda
      samples = samples + 1
    end do
    call compute_flow_statistics(stats, solver)
    energy_end = stats%kinetic_energy + 0.5_wp * sum(stats%mean_velocity**2)
    mean_power = mean_power / samples; mean_dissipation = mean_dissipation / samples
    mean_force_squared = mean_force_squared / samples
    if (is_root()) write(*, '(a,es12.5,a,es12.5,a,es12.5,a,f7.3)') '  <f.u> = ', mean_power, &
        ' m^2/s^3, <epsilon> = ', mean_dissipation, ', <u_rms> = ', mean_u_rms / samples, &
        ' m/s, <Re_lambda> = ', mean_re_lambda / samples
    call check_close(mean_power, mean_dissipation, 0.05_wp, 'stationary_power_input_equals_dissipation')
    if (is_root()) write(*, '(a,es12.5,a,es12.5)') '  (k_end - k_start)/W = ', (energy_end - energy_start) / &
        (samples * dt), ', forward-Euler forcing work dt <|f|^2>/2 = ', 0.5_wp * dt * mean_force_squared

    ! In-memory restart: copy the fluid state, pack/unpack the forcing, continue both.
    call setup(copy, forcing_copy, fx, fy, fz)
    copy%u = solver%u; copy%v = solver%v; copy%w = solver%w; copy%pressure = solver%pressure
    copy%explicit_old_u = solver%explicit_old_u; copy%explicit_old_v = solver%explicit_old_v
    copy%explicit_old_w = solver%explicit_old_w; copy%has_history = solver%has_history
    copy%dt_old = solver%dt_old; copy%time = solver%time; copy%step = solver%step
    words = forcing_pack_state(forcing)
    call forcing_unpack_state(forcing_copy, words)
    do step = 1, 20
      call forced_step(solver, forcing, fx, fy, fz)
      call forced_step(copy, forcing_copy, fx, fy, fz)
    end do
    same = all(solver%u == copy%u) .and. all(solver%v == copy%v) .and. all(solver%w == copy%w)
    call check(same, 'restart_with_forcing_bit_for_bit')
  end subroutine power_balance_and_restart

  subroutine write_fields(file_path)
    character(len=*), intent(in) :: file_path
    type(fluid_solver_t) :: solver
    type(ep_forcing_t) :: forcing
    real(wp), allocatable :: fx(:,:,:), fy(:,:,:), fz(:,:,:)
    type(h5_file_t) :: file
    integer :: step
    logical :: written
    call setup(solver, forcing, fx, fy, fz)
    do step = 1, 40
      call forced_step(solver, forcing, fx, fy, fz)
    end do
    call h5_create(file, file_path)
    associate (g => solver%grid)
      call h5_write_slab(file, 'u', solver%u(1:g%nx, 1:g%ny, 1:g%nz_local), g%z_offset, [g%nx, g%ny, g%nz])
      call h5_write_slab(file, 'v', solver%v(1:g%nx, 1:g%ny, 1:g%nz_local), g%z_offset, [g%nx, g%ny, g%nz])
      call h5_write_slab(file, 'w', solver%w(1:g%nx, 1:g%ny, 1:g%nz_local), g%z_offset, [g%nx, g%ny, g%nz])
    end associate
    call h5_close(file)
    call h5_open(file, file_path, writable=.false.)
    written = h5_exists(file, 'u') .and. h5_exists(file, 'v') .and. h5_exists(file, 'w')
    call h5_close(file)
    call check(written, 'fields_written')
    ! From rest, only the forcing moves the fluid: a zero field would make the rank comparison empty.
    associate (g => solver%grid)
      call check(global_max(maxval(abs(solver%u(1:g%nx, 1:g%ny, 1:g%nz_local)))) > 0.0_wp, 'forced_flow_moving')
    end associate
  end subroutine write_fields
end program test_forced_box
