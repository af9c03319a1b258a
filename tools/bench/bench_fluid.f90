!> Fluid benchmark (tools/bench.sh, `make bench`): medians of the time per step and its parts at
!> one grid size on the ranks it is started with. Usage: mpirun -np R bench_fluid N STEPS
!> Prints one line: N ranks fft_pair_ms poisson_ms step_ms explicit_ms projection_ms halo_ms io_ms
!> poisson_copy_ms (medians over STEPS repetitions; the categories are medians of per-step timer
!> increments). poisson_ms is the solve as the step does it (in FFTW's buffer: poisson_solve_in_buffer);
!> poisson_copy_ms the poisson_solve API that copies a halo field in and the solution out.
!> The FFT pair, both solves and a step are timed in turn inside each repetition, so a change of
!> the machine's load during the run affects the numerators and denominators of the ratios alike.
program bench_fluid
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, parallel_stop, n_ranks, is_root, barrier, global_max
  use wall_clock, only: wall_time
  use file_system, only: make_directory
  use hdf5_files, only: h5_finalize
  use field_output, only: field_snapshot_t, field_snapshot_begin, field_snapshot_add, field_snapshot_end, &
                          at_x_face, at_y_face, at_z_face, at_cell_centre
  use poisson_fft, only: poisson_solve, poisson_solve_in_buffer, fft_round_trip
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_advance
  use timer_registry, only: timer_seconds, timer_reset_all, timer_breakdown
  use initial_fields, only: set_random_field
  use sample_statistics, only: median
  implicit none
  type(fluid_solver_t) :: solver
  type(field_snapshot_t) :: snapshot
  character(len=32) :: argument
  integer :: n, steps, s
  real(wp), allocatable :: fft_times(:), poisson_times(:), copy_times(:), step_times(:), parts(:, :), io_times(:)
  real(wp) :: t0, before(3), dt
  integer, parameter :: explicit_part = 1, poisson_part = 2, halo_part = 3   ! columns of parts
  integer :: unit
  logical :: ok
  character(len=80), allocatable :: lines(:)

  call parallel_start()
  call get_command_argument(1, argument); read(argument, *) n
  call get_command_argument(2, argument); read(argument, *) steps
  allocate(fft_times(steps), poisson_times(steps), copy_times(steps), step_times(steps), parts(steps, 3), &
           io_times(3))
  ! Water in a 1 mm box, random field of rms 5 cm/s, explicit diffusion (the target case of docs/studies/performance.md, Fluid).
  call fluid_solver_create(solver, grid_config_t(nx=n, ny=n, nz=n, length_x=1.0e-3_wp, length_y=1.0e-3_wp, &
      length_z=1.0e-3_wp), fluid_config_t(viscosity=1.0e-6_wp, density=997.0_wp, viscous_scheme='explicit', &
      fft_planning='estimate'))
  call set_random_field(solver, 1_i8, 0.05_wp, 2.0_wp * 6.283185307179586_wp / 1.0e-3_wp)
  dt = 0.1_wp * (1.0e-3_wp / n)**2 / 1.0e-6_wp / 12.0_wp
  call fluid_advance(solver, dt)   ! warm-up (first step is the Euler start)
  call timer_reset_all()
  do s = 1, steps
    call barrier(); t0 = wall_time()
    call fft_round_trip(solver%poisson)
    fft_times(s) = global_max(wall_time() - t0)
    ! The copying solve refills the buffer from work (zero): the round trips' unnormalised growth
    ! does not accumulate, and the in-buffer solve then works on finite values.
    call barrier(); t0 = wall_time()
    call poisson_solve(solver%poisson, solver%work, solver%explicit_u)
    copy_times(s) = global_max(wall_time() - t0)
    call barrier(); t0 = wall_time()
    call poisson_solve_in_buffer(solver%poisson)
    poisson_times(s) = global_max(wall_time() - t0)
    before = solver_timers()
    call barrier(); t0 = wall_time()
    call fluid_advance(solver, dt)
    step_times(s) = global_max(wall_time() - t0)
    parts(s, :) = solver_timers() - before
  end do
  if (is_root()) call make_directory('bench_io', ok)
  call barrier()
  do s = 1, 3
    call barrier(); t0 = wall_time()
    call field_snapshot_begin(snapshot, s, 0.0_wp, [n, n, n], [1.0e-3_wp, 1.0e-3_wp, 1.0e-3_wp], directory='bench_io')
    call field_snapshot_add(snapshot, 'u', solver%u(1:n, 1:n, 1:solver%grid%nz_local), solver%grid%z_offset, at_x_face)
    call field_snapshot_add(snapshot, 'v', solver%v(1:n, 1:n, 1:solver%grid%nz_local), solver%grid%z_offset, at_y_face)
    call field_snapshot_add(snapshot, 'w', solver%w(1:n, 1:n, 1:solver%grid%nz_local), solver%grid%z_offset, at_z_face)
    call field_snapshot_add(snapshot, 'pressure', solver%pressure(1:n, 1:n, 1:solver%grid%nz_local), &
                            solver%grid%z_offset, at_cell_centre)
    call field_snapshot_end(snapshot)
    io_times(s) = global_max(wall_time() - t0)
  end do
  if (is_root()) write(*, '(i5,i3,8f11.3)') n, n_ranks, 1.0e3_wp * median(fft_times), 1.0e3_wp * median(poisson_times), &
      1.0e3_wp * median(step_times), 1.0e3_wp * median(parts(:, explicit_part)), &
      1.0e3_wp * median(parts(:, poisson_part)), 1.0e3_wp * median(parts(:, halo_part)), 1.0e3_wp * median(io_times), &
      1.0e3_wp * median(copy_times)
  ! The registry's per-step breakdown of the timed steps (tools/bench.sh prints it).
  lines = timer_breakdown(int(steps, i8), sum(step_times))
  if (is_root()) then
    open(newunit=unit, file='timer_breakdown.txt', status='replace', action='write')
    write(unit, '(a)') (trim(lines(s)), s = 1, size(lines))
    close(unit)
  end if
  call h5_finalize()
  call parallel_stop()

contains

  !> Seconds so far of the solver's timers: advection/diffusion, Poisson/projection, halo exchange.
  function solver_timers() result(seconds)
    real(wp) :: seconds(3)
    seconds = [timer_seconds(solver%timer_explicit), timer_seconds(solver%timer_poisson), &
               timer_seconds(solver%timer_halo)]
  end function solver_timers
end program bench_fluid
