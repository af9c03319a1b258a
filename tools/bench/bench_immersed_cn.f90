!> The Crank-Nicolson predictor with the immersed-boundary rows solved with hypre (immersed_predictor),
!> the tables of docs/studies/performance.md ("Crank-Nicolson with the immersed boundary") and
!> docs/studies/validation.md:
!> 1. the solver choice: BiCGSTAB and GMRES with the FFT Helmholtz preconditioner (Jacobi on the
!>    body rows), BoomerAMG and ILU(0), at nu dt / dx^2 = 0.1, 1, 10, for a sphere (D/dx = 12) and
!>    a tilted disk (aspect 5, 4.1 cells thick) in a driven 40^3 box; mean iterations per
!>    component solve and CPU time per whole step (after the first step's setup; CPU rather than
!>    wall time: the measuring machine was shared);
!>    the same with a moving sphere (nodes reclassified, matrices built every step);
!> 2. the simple-cubic sphere array (phi = 0.125) at D/dx = 8 and 12 to steady state: explicit
!>    diffusion at nu dt / dx^2 = 0.06 against CN at 1 and 5: K against Zick & Homsy (1982,
!>    J. Fluid Mech. 115, 13, Table 2: K = 4.292), steps and CPU time to steady state.
!> 3. the cost at equal error: CPU time until the superficial velocity stays within 0.1% of its
!>    steady value, explicit diffusion against CN.
!> Run by `make validate` (one rank).
program bench_immersed_cn
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root, global_sum
  use physical_constants, only: pi
  use wall_clock, only: wall_time
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: make_spheroid
  use hypre_solver, only: linear_solver_config_t
  use immersed_boundary, only: ibm_settings_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp
  character(len=16), parameter :: methods(2) = [character(len=16) :: 'bicgstab', 'gmres']
  character(len=16), parameter :: preconditioners(3) = [character(len=16) :: 'user', 'boomeramg', 'ilu']
  real(wp), parameter :: numbers(3) = [0.1_wp, 1.0_wp, 10.0_wp]
  character(len=8), parameter :: shapes(2) = [character(len=8) :: 'sphere', 'disk']
  integer :: s, r, m, p

  call parallel_start()
  if (is_root()) then
    print '(a)', '## Solver choice (40^3, driven, 6 steps, tolerance 1e-8; iterations per component solve, CPU ms per step)'
    print '(a)', '| body | nu dt/dx^2 | method | preconditioner | iterations (mean/max) | CPU ms per step |'
    print '(a)', '|---|---|---|---|---|---|'
  end if
  do s = 1, size(shapes)
    do r = 1, size(numbers)
      do m = 1, size(methods)
        do p = 1, size(preconditioners)
          call solver_row(shapes(s), numbers(r), methods(m), preconditioners(p), .false.)
        end do
      end do
    end do
  end do
  if (is_root()) then
    print '(a)', ''
    print '(a)', '## Moving sphere (U = 0.05 dx per step: the matrices are built every step)'
    print '(a)', '| body | nu dt/dx^2 | method | preconditioner | iterations (mean/max) | CPU ms per step |'
    print '(a)', '|---|---|---|---|---|---|'
  end if
  do r = 1, size(numbers)
    do p = 1, size(preconditioners)
      call solver_row('sphere', numbers(r), 'bicgstab', preconditioners(p), .true.)
    end do
  end do
  call sphere_array_table()
  if (is_root()) then
    print '(a)', ''
    print '(a)', '## Cost to steady state at equal error: CPU time until U stays within 0.1% of its steady value'
    print '(a)', '| D/dx | scheme | nu dt/dx^2 | steps | CPU s | CPU ms per step | steady K |'
    print '(a)', '|---|---|---|---|---|---|---|'
  end if
  call approach_to_steady(13, 'explicit', 0.06_wp)
  call approach_to_steady(13, 'crank_nicolson', 1.0_wp)
  call approach_to_steady(13, 'crank_nicolson', 5.0_wp)
  call approach_to_steady(19, 'explicit', 0.06_wp)
  call approach_to_steady(19, 'crank_nicolson', 1.0_wp)
  call approach_to_steady(19, 'crank_nicolson', 5.0_wp)
  ! 19 is prime (FFTW's slowest sizes, and CN+hypre does 10-20 FFT pairs per step): 24 is not.
  call approach_to_steady(24, 'explicit', 0.06_wp)
  call approach_to_steady(24, 'crank_nicolson', 1.0_wp)
  call approach_to_steady(24, 'crank_nicolson', 5.0_wp)
  call parallel_stop()

contains

  subroutine solver_row(shape, number, method, preconditioner, moving)
    character(len=*), intent(in) :: shape, method, preconditioner
    real(wp), intent(in) :: number
    logical, intent(in) :: moving
    integer, parameter :: cells = 40, steps = 6
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(1)
    type(ibm_settings_t) :: settings
    type(linear_solver_config_t) :: config
    real(wp) :: box, dx, dt, cpu_start, cpu_end, iterations
    integer :: step, most
    box = 1.0e-3_wp
    dx = box / cells
    grid_cfg = grid_config_t(nx=cells, ny=cells, nz=cells, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = 1000.0_wp
    fluid_cfg%viscosity = 1.0e-6_wp
    fluid_cfg%viscous_scheme = 'crank_nicolson'
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    if (shape == 'sphere') then
      motion(1)%shape = make_spheroid('sphere', 6.0_wp * dx, 1000.0_wp)
    else
      motion(1)%shape = make_spheroid('disk', 6.0_wp * dx, 1000.0_wp, 5.0_wp)
      motion(1)%orientation = [0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp] / norm2([0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp])
    end if
    motion(1)%centre = 0.5_wp * box + [0.13_wp, 0.27_wp, 0.41_wp] * dx
    settings%coupling = 'implicit'
    settings%fluid_density = fluid_cfg%density
    dt = number * dx**2 / fluid_cfg%viscosity
    if (moving) motion(1)%velocity = [0.05_wp * dx / dt, 0.02_wp * dx / dt, 0.0_wp]
    config%method = method
    config%preconditioner = preconditioner
    config%tolerance = 1.0e-8_wp     ! &fluid predictor_tolerance's default
    config%max_iterations = 500
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, &
                               driving_force=[2.5e-3_wp, 1.0e-3_wp, 0.0_wp], predictor_config=config))
    iterations = 0
    most = 0
    cpu_start = 0
    do step = 1, steps
      call immersed_step(scene, solver, dt)
      if (step == 1) then
        call cpu_time(cpu_start)
      else
        iterations = iterations + scene%predicted%sweeps
        most = max(most, scene%predicted%sweeps)
      end if
    end do
    call cpu_time(cpu_end)
    if (is_root()) print '(a,f5.1,a,f6.1,a,i0,a,f8.1,a)', '| '//trim(shape)//' | ', number, ' | '//trim(method)//' | '// &
        trim(merge('FFT + Jacobi    ', preconditioner, preconditioner == 'user'))//' | ', &
        iterations / (steps - 1), ' / ', most, ' | ', 1.0e3_wp * (cpu_end - cpu_start) / (steps - 1), ' |'
  end subroutine solver_row

  subroutine sphere_array_table()
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    integer, parameter :: grids(2) = [13, 19]
    real(wp), parameter :: cn_numbers(2) = [1.0_wp, 5.0_wp]
    real(wp) :: cpu
    integer :: g, n
    if (is_root()) then
      print '(a)', ''
      print '(a)', '## Sphere array phi = 0.125 to steady state (relative change of U per step < 1e-9)'
      print '(a)', '| D/dx | scheme | nu dt/dx^2 | K | error vs 4.292 | steps | iterations mean/max | CPU s | CPU ms per step |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|'
    end if
    do g = 1, size(grids)
      case%cells = grids(g)
      case%viscous_scheme = 'explicit'
      case%viscous_number = 0.06_wp
      call timed_run(case, result, cpu)
      call row('explicit', case, result, cpu)
      case%viscous_scheme = 'crank_nicolson'
      do n = 1, size(cn_numbers)
        case%viscous_number = cn_numbers(n)
        call timed_run(case, result, cpu)
        call row('CN + hypre', case, result, cpu)
      end do
    end do
  end subroutine sphere_array_table

  !> The sphere array of sphere_array_case (phi = 0.125, the same box, drive and sphere offset),
  !> stepped here so that the superficial velocity of every step is kept: the steps and CPU time
  !> until U stays within 0.1% of its steady value (relative change per step below 1e-11).
  subroutine approach_to_steady(cells, scheme, number)
    integer, intent(in) :: cells
    character(len=*), intent(in) :: scheme
    real(wp), intent(in) :: number
    integer, parameter :: max_steps = 40000
    real(wp), parameter :: box = 1.0e-3_wp, viscosity = 1.0e-6_wp, density = 1000.0_wp, drive = 2.5e-3_wp
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(1)
    type(ibm_settings_t) :: settings
    real(wp), allocatable :: velocity(:), cpu(:)
    real(wp) :: radius, dt, t0, t1, k_steady
    integer :: step, last, settled
    grid_cfg = grid_config_t(nx=cells, ny=cells, nz=cells, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = density
    fluid_cfg%viscosity = viscosity
    fluid_cfg%viscous_scheme = scheme
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    radius = (3.0_wp * 0.125_wp / (4.0_wp * pi))**(1.0_wp / 3.0_wp) * box
    motion(1)%shape = make_spheroid('sphere', radius, density)
    motion(1)%centre = 0.5_wp * box + [0.13_wp, 0.27_wp, 0.41_wp] * solver%grid%dx
    settings%coupling = 'implicit'
    settings%max_sweeps = 100
    settings%fluid_density = density
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, &
                               driving_force=[drive, 0.0_wp, 0.0_wp]))
    dt = number * solver%grid%dx**2 / viscosity
    allocate(velocity(max_steps), cpu(max_steps))
    call cpu_time(t0)
    last = max_steps
    do step = 1, max_steps
      call immersed_step(scene, solver, dt)
      velocity(step) = global_sum(sum(solver%u(cells, 1:cells, 1:solver%grid%nz_local))) / real(cells * cells, wp)
      call cpu_time(t1)
      cpu(step) = t1 - t0
      if (step > 10) then
        if (abs(velocity(step) - velocity(step - 1)) <= 1.0e-11_wp * abs(velocity(step))) then
          last = step
          exit
        end if
      end if
    end do
    settled = last
    do step = last, 1, -1
      if (abs(velocity(step) / velocity(last) - 1.0_wp) > 1.0e-3_wp) exit
      settled = step
    end do
    k_steady = drive * box**3 / (6.0_wp * pi * density * viscosity * radius * velocity(last))
    if (is_root()) print '(a,f6.2,a,f5.2,a,i0,a,f8.3,a,f7.2,a,f7.4,a)', '| ', 2.0_wp * radius / solver%grid%dx, &
        ' | '//trim(scheme)//' | ', number, ' | ', settled, ' | ', cpu(settled), ' | ', 1.0e3_wp * cpu(last) / last, &
        ' | ', k_steady, ' |'
  end subroutine approach_to_steady

  subroutine timed_run(case, result, cpu)
    type(sphere_array_case_t), intent(in) :: case
    type(sphere_array_result_t), intent(out) :: result
    real(wp), intent(out) :: cpu
    real(wp) :: t0, t1
    call cpu_time(t0)
    call run_sphere_array(case, result)
    call cpu_time(t1)
    cpu = t1 - t0
  end subroutine timed_run

  subroutine row(label, case, result, cpu)
    character(len=*), intent(in) :: label
    type(sphere_array_case_t), intent(in) :: case
    type(sphere_array_result_t), intent(in) :: result
    real(wp), intent(in) :: cpu
    if (is_root()) print '(a,f6.2,a,f5.2,a,f7.4,a,f7.3,a,i0,a,f6.2,a,i0,a,f8.2,a,f7.2,a)', '| ', result%diameter_cells, &
          ' | '//label//' | ', case%viscous_number, ' | ', result%drag_coefficient, ' | ', &
          100 * (result%drag_coefficient / zick_homsy_0125 - 1), '% | ', result%steps, ' | ', result%mean_sweeps, &
          ' / ', result%max_sweeps, ' | ', cpu, ' | ', 1.0e3_wp * cpu / result%steps, ' |'
  end subroutine row
end program bench_immersed_cn
