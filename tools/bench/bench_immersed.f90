!> Cost of the coupled step (immersed bodies in prescribed motion) against the fluid-only step, and
!> its parts (tools/bench.sh, `make bench`; docs/studies/performance.md, "Immersed boundary").
!> Usage: mpirun -np R bench_immersed N STEPS BODIES COUPLING [CLOCK [MESH_LEVEL [SHAPES]]]
!>   COUPLING = implicit | explicit; CLOCK = wall (default) | cpu (the process's CPU time: on a shared
!>   machine the 1-rank figures then do not count the time other processes hold the core);
!>   MESH_LEVEL >= 0: the ghost nodes see the icosphere of that level (&bodies geometry = 'mesh',
!>   20 4^level faces), -1 (default) the analytic spheroid;
!>   SHAPES = paper (default: needles and disks, below) | sphere (spheres of diameter 10 cells on a
!>   cubic lattice of ceiling(BODIES^(1/3)) sites per axis, moving and rotating as below) | mixed
!>   (needles, disks and spheres of the paper's size in turn on that lattice, their axes near the
!>   lattice diagonal: up to 128 bodies at 128^3 without contact).
!>
!> Water in a 1 mm box at N^3 with the explicit diffusion (AB2) and the incremental pressure, a
!> random field of rms 1 mm/s and a uniform drive. Bodies of the paper's size (volume-equivalent
!> radius 50 um, aspect ratio 5): body 1 a needle, body 2 a disk (34 um thick: 4.4 cells at 128^3),
!> then needles and disks alternately, one per octant of the box, each translating at about 1 mm/s
!> and rotating at 20 rad/s, so that every step reclassifies them. Each repetition times, with the
!> slowest rank's time:
!>   - one fluid-only step (fluid_predict with the drive, fluid_project, fluid_finish_step) on a
!>     second solver with the same field;
!>   - one coupled step (immersed_step, as the resolved scene takes it);
!>   - the same coupled step in its parts: the placement with the reclassification (ibm_set_bodies),
!>     the two impositions (ibm_impose: interior values and ghost sweeps), the loads (ibm_begin_step
!>     and ibm_step_loads), the cut-cell divergence, and the fluid stages between them.
!> Prints one line of medians (ms): the fluid-only step, the coupled step, their ratio, the parts,
!> the ghost nodes (all components and ranks), the sweeps of the last step and the stencil fallbacks.
program bench_immersed
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_INTEGER, MPI_SUM
  use agglo_kinds, only: wp, i8
  use parallel_env, only: parallel_start, parallel_stop, n_ranks, is_root, barrier, global_max, world
  use wall_clock, only: wall_time
  use fluid_solver, only: fluid_solver_t, fluid_solver_create, fluid_predict, fluid_project, fluid_finish_step
  use initial_fields, only: set_random_field
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use sample_statistics, only: median
  use spheroid, only: make_spheroid
  use quaternion, only: quaternion_from_axis_angle, quaternion_product
  use icosphere_mesh, only: build_icosphere_mesh
  use immersed_geometry, only: immersed_body_t
  use immersed_boundary, only: ibm_settings_t
  use immersed_placement, only: ibm_set_bodies
  use immersed_imposition, only: ibm_impose
  use immersed_loads, only: ibm_begin_step, ibm_step_loads
  use immersed_diagnostics, only: cell_divergence_max
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step, &
                            motion_body, motion_velocity
  implicit none
  integer, parameter :: n_parts = 6
  character(len=*), parameter :: part_names(n_parts) = [character(len=12) :: 'reclassify', 'impose u*', &
      'impose u', 'loads', 'divergence', 'fluid']
  real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 997.0_wp
  type(grid_config_t) :: grid_cfg
  type(fluid_config_t) :: fluid_cfg
  type(fluid_solver_t) :: fluid_only, coupled, parts_solver
  type(immersed_scene_t) :: scene, parts_scene
  type(prescribed_motion_t), allocatable :: motion(:)
  type(ibm_settings_t) :: settings
  character(len=32) :: argument, coupling, shapes
  logical :: use_cpu_clock
  integer :: n, steps, n_bodies, s, p, ghosts, fallbacks, c, mesh_level
  real(wp), allocatable :: t_fluid(:), t_coupled(:), t_parts(:, :)
  real(wp) :: dt, t0, drive(3), lap_start, part_seconds(n_parts)

  call parallel_start()
  call get_command_argument(1, argument); read(argument, *) n
  call get_command_argument(2, argument); read(argument, *) steps
  call get_command_argument(3, argument); read(argument, *) n_bodies
  call get_command_argument(4, coupling)
  call get_command_argument(5, argument)
  use_cpu_clock = (trim(argument) == 'cpu')
  mesh_level = -1
  call get_command_argument(6, argument)
  if (len_trim(argument) > 0) read(argument, *) mesh_level
  call get_command_argument(7, shapes)
  if (len_trim(shapes) == 0) shapes = 'paper'
  allocate(t_fluid(steps), t_coupled(steps), t_parts(n_parts, steps))

  grid_cfg = grid_config_t(nx=n, ny=n, nz=n, length_x=box, length_y=box, length_z=box)
  fluid_cfg = fluid_config_t(viscosity=viscosity, density=density, viscous_scheme='explicit', &
                             fft_planning='estimate', pressure_scheme='incremental')
  call fluid_solver_create(fluid_only, grid_cfg, fluid_cfg)
  call fluid_solver_create(coupled, grid_cfg, fluid_cfg)
  call fluid_solver_create(parts_solver, grid_cfg, fluid_cfg)
  call set_random_field(fluid_only, 1_i8, 1.0e-3_wp, 2.0_wp * 6.283185307179586_wp / box)
  call set_random_field(coupled, 1_i8, 1.0e-3_wp, 2.0_wp * 6.283185307179586_wp / box)
  call set_random_field(parts_solver, 1_i8, 1.0e-3_wp, 2.0_wp * 6.283185307179586_wp / box)
  ! Half the explicit viscous limit dx^2 / (12 nu) (docs/theory.md, time step).
  dt = 0.5_wp * (box / n)**2 / (12.0_wp * viscosity)
  drive = [5.0_wp, 0.0_wp, -2.0_wp]   ! N/m^3

  motion = bench_bodies(n_bodies)
  settings%coupling = trim(coupling)
  settings%fluid_density = density
  settings%tolerance = 1.0e-12_wp
  settings%max_sweeps = 50
  call immersed_scene_create(scene, coupled, motion, immersed_scene_options_t(settings=settings, driving_force=drive))
  call immersed_scene_create(parts_scene, parts_solver, motion, immersed_scene_options_t(settings=settings, &
                             driving_force=drive))

  call fluid_step()         ! warm-up (the first step is the Euler start)
  call immersed_step(scene, coupled, dt)
  call parts_step(t_parts(:, 1))
  do s = 1, steps
    call barrier(); t0 = clock()
    call fluid_step()
    t_fluid(s) = global_max(clock() - t0)
    call barrier(); t0 = clock()
    call immersed_step(scene, coupled, dt)
    t_coupled(s) = global_max(clock() - t0)
    call parts_step(t_parts(:, s))
  end do

  ghosts = 0
  fallbacks = 0
  do c = 1, 3
    ghosts = ghosts + scene%ibm%geometry%component(c)%n_ghost
    fallbacks = fallbacks + scene%ibm%geometry%component(c)%n_fallback
  end do
  call MPI_Allreduce(MPI_IN_PLACE, ghosts, 1, MPI_INTEGER, MPI_SUM, world)
  call MPI_Allreduce(MPI_IN_PLACE, fallbacks, 1, MPI_INTEGER, MPI_SUM, world)
  if (is_root()) then
    write(*, '(i5,i3,i5,1x,a9,3f9.2,*(f9.2))') n, n_ranks, n_bodies, trim(coupling), 1.0e3_wp * median(t_fluid), &
        1.0e3_wp * median(t_coupled), median(t_coupled) / median(t_fluid), &
        [(1.0e3_wp * median(t_parts(p, :)), p = 1, n_parts)]
    write(*, '(24x,a,i0,a,i0,a,i0,3a,i0,2a)') 'ghost nodes ', ghosts, ', sweeps (u*) ', scene%predicted%sweeps, &
        ', fallbacks ', fallbacks, '; clock ', trim(merge('cpu ', 'wall', use_cpu_clock)), &
        '; icosphere level (-1: analytic) ', mesh_level, '; shapes ', trim(shapes)
  end if
  call parallel_stop()

contains

  !> Seconds on the chosen clock.
  real(wp) function clock()
    if (use_cpu_clock) then
      call cpu_time(clock)
    else
      clock = wall_time()
    end if
  end function clock

  !> Needles and disks of the paper's size, one per octant (at most 8), moving and rotating.
  function bench_bodies(count) result(motion)
    integer, intent(in) :: count
    type(prescribed_motion_t), allocatable :: motion(:)
    real(wp), parameter :: radius = 50.0e-6_wp, aspect = 5.0_wp
    integer :: m, octant(3), sites, site(3)
    allocate(motion(count))
    if (trim(shapes) == 'sphere' .or. trim(shapes) == 'mixed') then
      sites = 1
      do while (sites**3 < count)
        sites = sites + 1
      end do
    end if
    do m = 1, count
      if (trim(shapes) == 'sphere') then
        ! Diameter 10 cells; lattice sites shifted off the grid's symmetry by a fraction of a cell.
        motion(m)%shape = make_spheroid('sphere', 5.0_wp * box / n, 1.0_wp)
        site = [mod(m - 1, sites), mod((m - 1) / sites, sites), (m - 1) / sites**2]
        motion(m)%centre = box * ((0.5_wp + site) / sites + [0.013_wp, 0.027_wp, 0.041_wp] * m / (8 * sites))
        motion(m)%orientation = quaternion_from_axis_angle([1.0_wp, 2.0_wp, 3.0_wp] + m, 0.3_wp * m)
        motion(m)%velocity = 1.0e-3_wp * [0.6_wp, -0.5_wp, 0.62_wp] * (1 + mod(m, 3))
        motion(m)%angular_velocity = 20.0_wp * [0.2_wp, 0.5_wp, -0.84_wp] * (1 - 2 * mod(m, 2))
        cycle
      end if
      if (trim(shapes) == 'mixed') then
        ! Parallel bodies along the lattice diagonal keep clear of their neighbours (at 128 bodies on
        ! 128^3, 21 cells apart: a needle's axis passes 17 cells from the next site, where a disk reaches 11
        ! and the needle 4); a turn of 0.02 m rad off the diagonal each keeps them off the grid's symmetry.
        select case (mod(m - 1, 3))
        case (0)
          motion(m)%shape = make_spheroid('needle', radius, 1.0_wp, aspect)
        case (1)
          motion(m)%shape = make_spheroid('disk', radius, 1.0_wp, aspect)
        case default
          motion(m)%shape = make_spheroid('sphere', radius, 1.0_wp)
        end select
        site = [mod(m - 1, sites), mod((m - 1) / sites, sites), (m - 1) / sites**2]
        motion(m)%centre = box * ((0.5_wp + site) / sites + [0.013_wp, 0.027_wp, 0.041_wp] * m / (8 * sites**2))
        ! body x onto (1, 1, 1)/sqrt(3): about (0, -1, 1) by acos(1/sqrt(3)), then the small turn
        motion(m)%orientation = quaternion_product(quaternion_from_axis_angle([1.0_wp, 2.0_wp, 3.0_wp] + m, 0.02_wp), &
            quaternion_from_axis_angle([0.0_wp, -1.0_wp, 1.0_wp], acos(1.0_wp / sqrt(3.0_wp))))
        motion(m)%velocity = 1.0e-3_wp * [0.6_wp, -0.5_wp, 0.62_wp] * (1 + mod(m, 3))
        motion(m)%angular_velocity = 20.0_wp * [0.2_wp, 0.5_wp, -0.84_wp] * (1 - 2 * mod(m, 2))
        cycle
      end if
      if (mod(m, 2) == 1) then
        motion(m)%shape = make_spheroid('needle', radius, 1.0_wp, aspect)
      else
        motion(m)%shape = make_spheroid('disk', radius, 1.0_wp, aspect)
      end if
      octant = [mod(m - 1, 2), mod((m - 1) / 2, 2), (m - 1) / 4]
      ! Octant centres, shifted off the grid's symmetry by a fraction of a cell.
      motion(m)%centre = box * (0.25_wp + 0.5_wp * octant + [0.013_wp, 0.027_wp, 0.041_wp] * m / 8)
      motion(m)%orientation = quaternion_from_axis_angle([1.0_wp, 2.0_wp, 3.0_wp] + m, 0.3_wp * m)
      motion(m)%velocity = 1.0e-3_wp * [0.6_wp, -0.5_wp, 0.62_wp] * (1 + mod(m, 3))
      motion(m)%angular_velocity = 20.0_wp * [0.2_wp, 0.5_wp, -0.84_wp] * (1 - 2 * mod(m, 2))
      if (mesh_level >= 0) call build_icosphere_mesh(motion(m)%shape, mesh_level, motion(m)%mesh)
    end do
  end function bench_bodies

  subroutine fluid_step()
    call fluid_predict(fluid_only, dt, force_u=scene%force_u, force_v=scene%force_v, force_w=scene%force_w)
    call fluid_project(fluid_only)
    call fluid_finish_step(fluid_only)
  end subroutine fluid_step

  !> The coupled step of immersed_step, each part timed (slowest rank, s).
  subroutine parts_step(seconds)
    real(wp), intent(out) :: seconds(n_parts)
    type(immersed_body_t) :: bodies(size(motion))
    real(wp) :: velocity(3, size(motion)), angular_velocity(3, size(motion)), lab_box(3), time
    integer :: m
    part_seconds = 0
    time = parts_solver%time + dt
    lab_box = [box, box, box]
    call barrier(); lap_start = clock()
    do m = 1, size(motion)
      bodies(m) = motion_body(motion(m), time, lab_box)
      velocity(:, m) = motion_velocity(motion(m), time)
      angular_velocity(:, m) = motion(m)%angular_velocity
    end do
    call ibm_set_bodies(parts_scene%ibm, parts_solver%grid, bodies, velocity, angular_velocity, .true.)
    call lap(1)
    call ibm_begin_step(parts_scene%ibm, parts_solver%grid, parts_solver%u, parts_solver%v, parts_solver%w)
    call lap(4)
    call fluid_predict(parts_solver, dt, force_u=parts_scene%force_u, force_v=parts_scene%force_v, &
                       force_w=parts_scene%force_w)
    call lap(6)
    call ibm_impose(parts_scene%ibm, parts_solver%grid, parts_solver%explicit_old_u, parts_solver%explicit_old_v, &
                    parts_solver%explicit_old_w, parts_scene%predicted)
    call lap(2)
    call fluid_project(parts_solver)
    call lap(6)
    call ibm_impose(parts_scene%ibm, parts_solver%grid, parts_solver%u, parts_solver%v, parts_solver%w, &
                    parts_scene%projected)
    call lap(3)
    parts_scene%divergence = cell_divergence_max(parts_solver%grid, parts_solver%u, parts_solver%v, parts_solver%w)
    call lap(5)
    call ibm_step_loads(parts_scene%ibm, parts_solver%grid, parts_solver%u, parts_solver%v, parts_solver%w, dt, &
                        parts_scene%force, parts_scene%torque)
    call lap(4)
    call fluid_finish_step(parts_solver)
    call lap(6)
    seconds = part_seconds
  end subroutine parts_step

  !> Add the time since the last lap (slowest rank) to part `part`.
  subroutine lap(part)
    integer, intent(in) :: part
    real(wp) :: now
    call barrier()
    now = clock()
    part_seconds(part) = part_seconds(part) + global_max(now - lap_start)
    lap_start = clock()
  end subroutine lap
end program bench_immersed
