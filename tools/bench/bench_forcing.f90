!> Forcing benchmark (tools/bench.sh, `make bench`, BENCH_PARTS=forcing): the Eswaran-Pope forcing's
!> cost per step (f written on every u, v, w face of the slab by the separable direct sums, then the
!> OU update and projection of the 28 modes) against a whole fluid step (Crank-Nicolson + AB2 + FFT
!> projection, as input/hit_box.nml) on N^3. Target (docs/studies/performance.md): forcing <= 10% of a fluid step.
!> Usage: mpirun -np R bench_forcing N REPEATS. Prints one line: N ranks forcing_ms step_ms percent
!> (means over REPEATS, the slowest rank's time).
program bench_forcing
  use agglo_kinds, only: wp, i8
  use physical_constants, only: two_pi
  use parallel_env, only: parallel_start, parallel_stop, n_ranks, is_root, barrier, global_max
  use wall_clock, only: wall_time
  use config_forcing, only: forcing_config_t
  use eswaran_pope_forcing, only: ep_forcing_t, forcing_init_on_grid, forcing_advance, forcing_set_fields
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_advance
  use initial_fields, only: set_random_field
  implicit none
  real(wp), parameter :: length = 1.0e-3_wp, nu = 1.0e-6_wp, rho = 997.0_wp, dt = 1.0e-4_wp
  type(fluid_solver_t) :: solver
  type(ep_forcing_t) :: forcing
  type(forcing_config_t) :: cfg
  real(wp), allocatable :: fx(:,:,:), fy(:,:,:), fz(:,:,:)
  character(len=32) :: argument
  integer :: n, repeats, step
  real(wp) :: t0, forcing_time, fluid_time

  call parallel_start()
  call get_command_argument(1, argument); read(argument, *) n
  call get_command_argument(2, argument); read(argument, *) repeats
  cfg%time_scale = 0.01_wp
  cfg%epsilon_star = 1.6e-4_wp          ! input/hit_box.nml
  call fluid_solver_create(solver, grid_config_t(nx=n, ny=n, nz=n, length_x=length, length_y=length, length_z=length), &
                           fluid_config_t(viscosity=nu, density=rho, viscous_scheme='crank_nicolson', fft_planning='estimate'))
  call set_random_field(solver, 7_i8, 7.7e-3_wp, 2.0_wp * two_pi / length)   ! the hit_box u_rms
  call forcing_init_on_grid(forcing, cfg, 20250224, solver%grid)
  allocate(fx, fy, fz, mold=solver%u)
  fx = 0; fy = 0; fz = 0
  ! Warm-up (first touches, FFTW buffers), then the timed loops.
  call forcing_set_fields(forcing, fx, fy, fz)
  call fluid_advance(solver, dt, fx, fy, fz)
  call barrier()
  t0 = wall_time()
  do step = 1, repeats
    call forcing_set_fields(forcing, fx, fy, fz)
    call forcing_advance(forcing, dt)
  end do
  forcing_time = global_max((wall_time() - t0) / repeats)
  call barrier()
  t0 = wall_time()
  do step = 1, repeats
    call fluid_advance(solver, dt, fx, fy, fz)
  end do
  fluid_time = global_max((wall_time() - t0) / repeats)
  if (is_root()) write(*, '(i5,i3,2f10.3,f8.2)') n, n_ranks, 1.0e3_wp * forcing_time, 1.0e3_wp * fluid_time, &
      100.0_wp * forcing_time / fluid_time
  call parallel_stop()
end program bench_forcing
