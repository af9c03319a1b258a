!> Staged fluid step against the fused one, and every part against the memory-bandwidth floor
!> (tools/bench.sh, `make bench`; docs/studies/performance.md, "Staged step and the roofline").
!> Usage: mpirun -np R bench_stages N STEPS SCHEME     (SCHEME = explicit | crank_nicolson)
!>
!> Each repetition times, in turn and each with the slowest rank's time: one FFT pair, one fused
!> step (fluid_advance), one staged step (fluid_predict, fluid_project, fluid_finish_step, each
!> timed), and the Poisson solve alone (in FFTW's buffer, as the step does it). Then a STREAM-like
!> triad a = b + s c runs on every rank at once, on arrays of 8 M doubles per rank (far beyond the
!> last-level cache): the machine's memory bandwidth on the same cores, the floor of any sweep.
!> Prints the minima over the repetitions (the least-disturbed run on a shared machine) and, for
!> the ratios, also their medians; then per stage (medians: a part without the Poisson solve is
!> the median of its per-repetition difference, robust where a minimum of differences is not) its
!> ns per grid point, the bytes per point it moves (STREAM's count: 8 bytes per array element read
!> and per element written, no write-allocate), the floor bytes / bandwidth, and the stage's time
!> in multiples of the floor.
program bench_stages
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, parallel_stop, n_ranks, is_root, barrier, global_max, global_sum
  use wall_clock, only: wall_time
  use poisson_fft, only: poisson_solve_in_buffer, fft_round_trip
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_advance, fluid_predict, fluid_project, &
                          fluid_finish_step
  use initial_fields, only: set_random_field
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use sample_statistics, only: median
  implicit none
  type(grid_config_t) :: grid_cfg
  type(fluid_config_t) :: fluid_cfg
  integer, parameter :: triad_length = 8 * 1024 * 1024, triad_repetitions = 10
  type(fluid_solver_t) :: fused, staged
  character(len=32) :: argument, scheme
  integer :: n, steps, s
  real(wp), allocatable :: fft(:), step_fused(:), step_staged(:), predict(:), project(:), finish(:), poisson(:)
  real(wp) :: t0, t1, t2, dt, bandwidth, points_per_rank, cn_bytes
  logical :: cn

  call parallel_start()
  call get_command_argument(1, argument); read(argument, *) n
  call get_command_argument(2, argument); read(argument, *) steps
  call get_command_argument(3, scheme)
  cn = (trim(scheme) == 'crank_nicolson')
  allocate(fft(steps), step_fused(steps), step_staged(steps), predict(steps), project(steps), finish(steps), &
           poisson(steps))
  ! Water in a 1 mm box, random field of rms 5 cm/s (the target case of docs/studies/performance.md, Fluid).
  grid_cfg = grid_config_t(nx=n, ny=n, nz=n, length_x=1.0e-3_wp, length_y=1.0e-3_wp, length_z=1.0e-3_wp)
  fluid_cfg = fluid_config_t(viscosity=1.0e-6_wp, density=997.0_wp, viscous_scheme=trim(scheme), fft_planning='estimate')
  call fluid_solver_create(fused, grid_cfg, fluid_cfg)
  call fluid_solver_create(staged, grid_cfg, fluid_cfg)
  call set_random_field(fused, 1_i8, 0.05_wp, 2.0_wp * 6.283185307179586_wp / 1.0e-3_wp)
  call set_random_field(staged, 1_i8, 0.05_wp, 2.0_wp * 6.283185307179586_wp / 1.0e-3_wp)
  dt = 0.1_wp * (1.0e-3_wp / n)**2 / 1.0e-6_wp / 12.0_wp
  call fluid_advance(fused, dt)   ! warm-up (the first step is the Euler start)
  call staged_step()
  do s = 1, steps
    call barrier(); t0 = wall_time()
    call fft_round_trip(fused%poisson)
    fft(s) = global_max(wall_time() - t0)
    call barrier(); t0 = wall_time()
    call fluid_advance(fused, dt)
    step_fused(s) = global_max(wall_time() - t0)
    call barrier(); t0 = wall_time()
    call fluid_predict(staged, dt)
    t1 = wall_time()
    call fluid_project(staged)
    t2 = wall_time()
    call fluid_finish_step(staged)
    step_staged(s) = global_max(wall_time() - t0)
    predict(s) = global_max(t1 - t0); project(s) = global_max(t2 - t1); finish(s) = global_max(wall_time() - t2)
    ! The Poisson solve alone, on the buffer the projection just left (finite values).
    call barrier(); t0 = wall_time()
    call poisson_solve_in_buffer(staged%poisson)
    poisson(s) = global_max(wall_time() - t0)
  end do
  bandwidth = triad_bandwidth()
  points_per_rank = real(n, wp)**3 / n_ranks

  if (is_root()) then
    write(*, '(a,i4,a,i2,2a,f7.2,a)') 'N =', n, ', ranks =', n_ranks, ', ', trim(scheme)//' viscous term; triad bandwidth', &
        bandwidth, ' GB/s (all ranks)'
    write(*, '(a,3f9.2,a,2f7.3,a,2f6.2)') '  ms (min): FFT pair, fused step, staged step', 1.0e3_wp * minval(fft), &
        1.0e3_wp * minval(step_fused), 1.0e3_wp * minval(step_staged), '; staged/fused min, median', &
        minval(step_staged) / minval(step_fused), median(step_staged / step_fused), '; fused/FFT min, median', &
        minval(step_fused) / minval(fft), median(step_fused / fft)
    write(*, '(a)') '  stage (medians)                            ms   ns/pt   B/pt  floor ns/pt  x floor'
    ! Predictor sweep: reads u, v, w and E^{n-1}, writes u* (over E^{n-1}) and E^n: 12 arrays.
    ! Crank-Nicolson adds per component a copy into the FFT buffer and back (4 arrays) and an FFT pair.
    cn_bytes = 0
    if (cn) cn_bytes = 3 * 4 * 8
    call stage_line('predictor (sweep + halos'//trim(merge(' + 3 Helmholtz)', ')              ', cn)), &
                    median(predict), 96.0_wp + cn_bytes)
    ! Projection without the Poisson solve: the divergence reads u*, v*, w* and writes the buffer
    ! (4 arrays); the correction reads and writes u*, v*, w* in place, reads phi, reads and writes p
    ! (9); Crank-Nicolson also keeps L phi (2) and reads it back (1).
    call stage_line('projection - Poisson (div, correction, p)', median(project - poisson), &
                    merge(128.0_wp, 104.0_wp, cn))
    call stage_line('Poisson solve (in buffer; FFT-bound)', median(poisson), 0.0_wp)
    call stage_line('finish (history rotation)', median(finish), 0.0_wp)
    ! The fused sweep computes the divergence from the planes still in cache (8 instead of 32).
    call stage_line('fused step (without the Poisson solve)', median(step_fused - poisson), &
                    merge(320.0_wp, 176.0_wp, cn))
    call stage_line('staged step (without the Poisson solve)', median(step_staged - poisson), &
                    merge(320.0_wp, 200.0_wp, cn))
  end if
  call parallel_stop()

contains

  subroutine staged_step()
    call fluid_predict(staged, dt)
    call fluid_project(staged)
    call fluid_finish_step(staged)
  end subroutine staged_step

  !> One table line: time (s) of a stage for the whole grid, bytes per grid point (0: not a sweep).
  subroutine stage_line(label, seconds, bytes)
    character(len=*), intent(in) :: label
    real(wp), intent(in) :: seconds, bytes
    real(wp) :: ns_per_point, floor
    character(len=42) :: text
    text = label
    ! ns per point of the whole grid: rank-parallel time over all points, as the bandwidth is.
    ns_per_point = 1.0e9_wp * seconds / (points_per_rank * n_ranks)
    if (bytes > 0) then
      floor = bytes / bandwidth
      write(*, '(2x,a42,f9.2,f8.2,f7.0,f13.2,f9.2)') text, 1.0e3_wp * seconds, ns_per_point, bytes, floor, &
          ns_per_point / floor
    else
      write(*, '(2x,a42,f9.2,f8.2,a7,a13,a9)') text, 1.0e3_wp * seconds, ns_per_point, '-', '-', '-'
    end if
  end subroutine stage_line

  !> GB/s of a = b + s c on every rank at once (STREAM's triad and byte count: 24 bytes per
  !> element), the best of triad_repetitions runs, each timed by the slowest rank.
  real(wp) function triad_bandwidth() result(gigabytes_per_second)
    real(wp), allocatable :: a(:), b(:), c(:)
    real(wp) :: best, scalar
    integer :: r, i
    allocate(a(triad_length), b(triad_length), c(triad_length))
    a = 0; b = 1; c = 2; scalar = 3
    best = huge(1.0_wp)
    do r = 1, triad_repetitions
      call barrier(); t0 = wall_time()
      do i = 1, triad_length
        a(i) = b(i) + scalar * c(i)
      end do
      best = min(best, global_max(wall_time() - t0))
      scalar = scalar + a(1 + mod(r, triad_length)) * 1.0e-30_wp   ! keeps the loop from being removed
    end do
    gigabytes_per_second = global_sum(24.0_wp * triad_length) / best * 1.0e-9_wp
    if (scalar < 0) write(*, *) a(1)
  end function triad_bandwidth
end program bench_stages
