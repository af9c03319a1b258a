!> Benchmark of the particle system's broad phase (module broad_phase) and of one pair interaction
!> of N spheres (docs/studies/performance.md, "Broad phase"): N = 10^3, 10^4, 10^5 spheres of
!> radius 2 um at random (overlaps allowed: only the search is timed) in a periodic cube at volume
!> fractions 0.34% (10^5 such spheres in a 1 mm box) and 10%, gap 500 nm (the DLVO cut-off of
!> docs/theory.md, "Particle system"). Per case: cells per side, near pairs, distance tests per
!> body, the cell-list search and the all-pairs search (N <= 10^4) in ms of CPU time (medians of 5), and
!> particle_system_interact of the spheres with DLVO and collisions (broad phase, record merge,
!> closest points, collision sweeps, DLVO) in ms and in ns per body.
!> Usage: bench_broad_phase.
program bench_broad_phase
  use agglo_kinds, only: wp, i8
  use random_stream, only: random_stream_t, stream_seed, stream_uniform
  use broad_phase, only: broad_phase_t, broad_phase_find, all_near_pairs
  use sample_statistics, only: median
  use config_dlvo, only: dlvo_config_t
  use config_collision, only: collision_config_t
  use dlvo, only: dlvo_setup, dlvo_cutoff_gap
  use collision, only: collision_setup
  use spheroid, only: spheroid_t, make_spheroid
  use rigid_body, only: rigid_body_t, rigid_body_of_spheroid, integrator_euler
  use particle_system, only: particle_models_t, particle_system_t, particle_system_create, particle_system_interact
  implicit none
  integer, parameter :: repeats = 5, counts(3) = [1000, 10000, 100000]
  real(wp), parameter :: radius = 2.0e-6_wp, fractions(2) = [0.0034_wp, 0.10_wp]
  type(broad_phase_t) :: finder
  type(random_stream_t) :: stream
  type(particle_models_t) :: models
  type(spheroid_t) :: sphere
  real(wp), allocatable :: positions(:,:), radii(:)
  type(rigid_body_t), allocatable :: bodies(:)
  type(particle_system_t) :: system
  integer, allocatable :: first(:), second(:)
  real(wp) :: box, gap, seconds(repeats), search_ms, brute_ms, interact_ms, t0
  integer :: c, f, i, r, n
  character(len=16) :: brute_text

  models%dlvo = .true.
  call dlvo_setup(models%dlvo_model, dlvo_config_t(), radius)
  models%collisions = .true.
  call collision_setup(models%collision_model, collision_config_t())
  models%integrator = integrator_euler
  gap = dlvo_cutoff_gap(models%dlvo_model)
  models%interaction_gap = gap
  sphere = make_spheroid('sphere', radius, 2710.0_wp)
  write(*, '(a,es9.2,a,es9.2,a)') 'broad phase of N spheres, radius ', radius, ' m, gap ', gap, &
      ' m (CPU time, medians of 5 repeats)'
  write(*, '(a)') '  fraction       N  cells  near_pairs  tests/N  cell_list_ms  all_pairs_ms  interact_ms  interact_ns/body'
  call stream_seed(stream, 1_i8, 1)
  do f = 1, size(fractions)
    do c = 1, size(counts)
      n = counts(c)
      box = (real(n, wp) * (4.0_wp / 3.0_wp) * acos(-1.0_wp) * radius**3 / fractions(f))**(1.0_wp / 3.0_wp)
      if (allocated(positions)) deallocate(positions, radii, bodies)
      allocate(positions(3, n), radii(n), bodies(n))
      radii = radius
      do i = 1, n
        positions(:, i) = box * [stream_uniform(stream), stream_uniform(stream), stream_uniform(stream)]
      end do
      do r = 1, repeats
        t0 = cpu_seconds()
        call broad_phase_find(finder, positions, radii, [box, box, box], gap)
        seconds(r) = cpu_seconds() - t0
      end do
      search_ms = 1.0e3_wp * median(seconds)
      brute_text = '-'
      if (n <= 10000) then
        t0 = cpu_seconds()
        call all_near_pairs(positions, radii, [box, box, box], gap, first, second)
        brute_ms = 1.0e3_wp * (cpu_seconds() - t0)
        write(brute_text, '(f12.2)') brute_ms
        if (size(first) /= finder%count) error stop 'bench_broad_phase: the cell list and all pairs disagree'
      end if
      do i = 1, n
        call rigid_body_of_spheroid(bodies(i), sphere, positions(:, i), [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp])
      end do
      call particle_system_create(system, spread(sphere, 1, n), bodies, models, box_length=[box, box, box])
      do r = 1, repeats
        system%pairs%active = .false.      ! closest points recomputed (warm-started) every repeat
        t0 = cpu_seconds()
        call particle_system_interact(system, 1.0e-7_wp)
        seconds(r) = cpu_seconds() - t0
      end do
      interact_ms = 1.0e3_wp * median(seconds)
      write(*, '(f9.4,i9,i7,i12,f9.2,f14.3,a14,f13.3,f18.1)') fractions(f), n, finder%cells(1), finder%count, &
          real(finder%tests, wp) / n, search_ms, trim(brute_text), interact_ms, 1.0e6_wp * interact_ms / n
    end do
  end do
contains

  !> CPU time of the process (s): on a shared machine the wall time measures the other jobs.
  real(wp) function cpu_seconds()
    call cpu_time(cpu_seconds)
  end function cpu_seconds
end program bench_broad_phase
