!> The Crank-Nicolson predictor with the immersed-boundary rows solved with hypre (immersed_predictor):
!> - simple-cubic sphere array, phi = 0.125, D/dx = 8.06 (13^3): at nu dt / dx^2 = 0.06 (below the
!>   explicit-diffusion limit) the steady K equals the explicit-diffusion run's to 0.1% (the same
!>   steady equations; the splitting's dt-dependence, docs/studies/validation.md, is below that there);
!> - at nu dt / dx^2 = 1 and 5 (8 and 40 times the explicit-diffusion limit 1/8 of this grid's
!>   AB2 step) K within 5% of Zick & Homsy (1982, J. Fluid Mech. 115, 13, Table 2: K = 4.292),
!>   steady in fewer than a fifth of the explicit run's steps, the reduced solve in a few GMRES iterations (below);
!> - after the predictor solve, u* satisfies every ghost row (Eq. 7 with the trilinear mirror
!>   stencil) and every interior row (u = U + Omega x r) of a translating, spinning sphere and a
!>   tilted needle to 1e-9 of the velocity scale (the solve to 1e-12), at nu dt / dx^2 = 10;
!> - the global momentum budget of the box closes to 1e-10 relative with the rows' momentum in the
!>   loads (a translating, oscillating sphere and a rotating needle: nodes change status, the
!>   matrices are rebuilt every step) at nu dt / dx^2 = 2, the solve to 1e-11;
!> - a new dt on fixed bodies (only the Helmholtz values replaced in the hypre matrices) gives the
!>   loads of matrices built afresh for that dt, to 1e-9 (both solves to 1e-12);
!> - a slowly moving sphere: the rows that keep their structure get new values only, with the
!>   loads of solvers created afresh every step, to 1e-9;
!> - the default method (GMRES on the ghost rows) gives hypre's BiCGSTAB solution on the whole
!>   system: a moving sphere's loads and velocity field to 1e-9 (both solves to 1e-12); its
!>   preconditioner's sparse matrix differs from the capacitance matrix formed column by column
!>   by no more than the Green's function's terms outside the window, and by under 1% of its
!>   largest entry; the sphere array's reduced solves take at most 4 / 6 iterations at
!>   nu dt / dx^2 = 1 / 5 (3 / 4 measured);
!> - a sphere creeping 1e-6 cells per step (no node changes status, no stencil changes): no
!>   component matrix is built again after the first step, only values are written; then a jump of
!>   half a cell (nodes change status): the matrices of the new pattern are built.
! checks: 28
program test_immersed_cn
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, global_sum
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: make_spheroid
  use immersed_boundary, only: ibm_settings_t, rigid_velocity
  use fluid_solver, only: fluid_predict
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  use immersed_predictor, only: default_predictor_config, immersed_predictor_reclassified
  use immersed_nodes, only: ghost_row_diagonal
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp   ! Zick & Homsy 1982, Table 2, phi = 0.125
  !> Largest residuals of the body rows on u* and the velocity scale (check_rows_satisfied).
  type :: row_check_t
    real(wp) :: worst_ghost = 0, worst_interior = 0, scale = 0
    integer :: ghosts = 0, interiors = 0
  end type row_check_t
  type(sphere_array_case_t) :: case
  type(sphere_array_result_t) :: explicit, small, large
  real(wp) :: numbers(2) = [1.0_wp, 5.0_wp]
  integer :: n

  call parallel_start()
  call test_start('immersed_cn')
  case%cells = 13
  case%steady_tolerance = 1.0e-8_wp
  case%viscous_number = 0.06_wp
  call run_sphere_array(case, explicit)
  call report('explicit', explicit)
  case%viscous_scheme = 'crank_nicolson'
  call run_sphere_array(case, small)
  call report('crank_nicolson', small)
  call check(small%steady, 'small_dt_reaches_steady_state')
  call check_close(small%drag_coefficient, explicit%drag_coefficient, 1.0e-3_wp, 'small_dt_same_drag_as_explicit')
  do n = 1, size(numbers)
    case%viscous_number = numbers(n)
    call run_sphere_array(case, large)
    call report('crank_nicolson', large)
    call check(large%steady, 'large_dt_reaches_steady_state')
    call check_close(large%drag_coefficient, zick_homsy_0125, 0.05_wp, 'large_dt_drag_zick_homsy_5pc')
    call check_below(real(large%steps, wp), 0.2_wp * explicit%steps, 'large_dt_steady_in_fewer_steps')
    ! The reduced solve with the local capacitance preconditioner: 3 and 4 iterations measured
    ! (7 and 10 with the Helmholtz operator among the ghost nodes as preconditioner).
    call check_below(real(large%max_sweeps, wp), merge(4.0_wp, 6.0_wp, n == 1), 'large_dt_few_gmres_iterations')
    call check_close(large%force(1), large%drive(1), 1.0e-6_wp, 'large_dt_steady_load_equals_drive')
  end do
  call check_rows_satisfied()
  call check_momentum_budget()
  call check_new_dt_same_as_rebuild()
  call check_slow_body_same_as_creation()
  call check_values_only_without_status_change()
  call check_capacitance_same_as_hypre()
  call test_finish()

contains

  subroutine report(label, result)
    character(len=*), intent(in) :: label
    type(sphere_array_result_t), intent(in) :: result
    character(len=160) :: text
    write(text, '(a,f6.2,a,f7.4,a,f7.3,a,i0,a,f6.2,a,i0)') ' nu dt/dx^2 ', case%viscous_number, ' K ', &
        result%drag_coefficient, ' error ', 100 * (result%drag_coefficient / zick_homsy_0125 - 1), '% steps ', &
        result%steps, ' iterations mean ', result%mean_sweeps, ' max ', result%max_sweeps
    print '(a)', label//trim(text)
  end subroutine report

  !> One predictor solve (the staged step's first stage, as immersed_step calls it), then every
  !> ghost row's and interior row's residual on u*, over the velocity scale.
  subroutine check_rows_satisfied()
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t), target :: scene
    type(prescribed_motion_t) :: motion(2)
    type(ibm_settings_t) :: settings
    type(row_check_t) :: rows
    real(wp) :: dt, box
    box = 1.0e-3_wp
    grid_cfg = grid_config_t(nx=20, ny=20, nz=20, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = 1000.0_wp
    fluid_cfg%viscosity = 1.0e-6_wp
    fluid_cfg%pressure_scheme = 'incremental'
    fluid_cfg%viscous_scheme = 'crank_nicolson'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 1.0e-3_wp; solver%v = -0.5e-3_wp; solver%w = 0.2e-3_wp; solver%pressure = 0
    motion(1)%shape = make_spheroid('sphere', 0.2_wp * box, 1000.0_wp)
    motion(1)%centre = [0.31_wp, 0.46_wp, 0.52_wp] * box
    motion(1)%velocity = [2.0e-3_wp, 1.0e-3_wp, -0.5e-3_wp]
    motion(1)%angular_velocity = [0.0_wp, 3.0_wp, 5.0_wp]
    motion(2)%shape = make_spheroid('needle', 0.15_wp * box, 1000.0_wp, 2.0_wp)
    motion(2)%centre = [0.75_wp, 0.7_wp, 0.93_wp] * box
    motion(2)%orientation = [0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp] / norm2([0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp])
    motion(2)%angular_velocity = [1.0_wp, 4.0_wp, 2.0_wp]
    settings%coupling = 'implicit'
    settings%fluid_density = fluid_cfg%density
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, &
                               driving_force=[2.0_wp, 0.0_wp, 0.0_wp], predictor_config=default_predictor_config(1.0e-12_wp, 200)))
    dt = 10.0_wp * solver%grid%dx**2 / fluid_cfg%viscosity
    scene%predictor%ibm => scene%ibm
    call fluid_predict(solver, dt, scene%predictor, force_u=scene%force_u, force_v=scene%force_v, &
                       force_w=scene%force_w)
    call component_rows(scene, 1, solver%explicit_old_u, rows)
    call component_rows(scene, 2, solver%explicit_old_v, rows)
    call component_rows(scene, 3, solver%explicit_old_w, rows)
    print '(a,i0,a,es10.2,a,i0,a,es10.2,a,i0,a)', 'rows on u*: ', rows%ghosts, ' ghost rows, worst ', &
        rows%worst_ghost / rows%scale, '; ', rows%interiors, ' interior rows, worst ', rows%worst_interior / rows%scale, &
        ' (of the velocity scale; ', scene%predictor%report%sweeps, ' iterations at nu dt/dx^2 = 10)'
    call check(rows%ghosts > 100 .and. rows%interiors > 100, 'bodies_have_ghost_and_interior_rows')
    call check_below(rows%worst_ghost / rows%scale, 1.0e-9_wp, 'predictor_satisfies_ghost_rows')
    call check_below(rows%worst_interior / rows%scale, 1.0e-9_wp, 'predictor_satisfies_interior_rows')
  end subroutine check_rows_satisfied

  !> (1 + kappa w_G) u_G + kappa sum_{j /= G} w_j u_j - (1 + kappa) u_B and u - u_rigid of
  !> component c on one rank (local plane = global plane), into the running maxima.
  subroutine component_rows(scene, c, field, rows)
    type(immersed_scene_t), intent(in) :: scene
    integer, intent(in) :: c
    real(wp), intent(in) :: field(0:, 0:, 0:)
    type(row_check_t), intent(inout) :: rows
    real(wp) :: row, u_b
    integer :: g, m, corner
    associate (nodes => scene%ibm%geometry%component(c), arms => scene%ibm%arms(c))
      do g = 1, nodes%n_ghost
        associate (ghost => nodes%ghost(g))
          u_b = rigid_velocity(scene%ibm, ghost%body, c, arms%surface(:, g))
          row = field(ghost%node(1), ghost%node(2), ghost%node(3)) - (1.0_wp + ghost%extrapolation) * u_b
          do corner = 1, 8
            row = row + ghost%extrapolation * ghost%weight(corner) * &
                  field(ghost%stencil(1, corner), ghost%stencil(2, corner), ghost%stencil(3, corner))
          end do
          rows%worst_ghost = max(rows%worst_ghost, abs(row))
          rows%scale = max(rows%scale, abs(u_b))
        end associate
      end do
      do m = 1, nodes%n_interior
        row = field(nodes%interior(1, m), nodes%interior(2, m), nodes%interior(3, m)) - &
              rigid_velocity(scene%ibm, nodes%interior_body(m), c, arms%interior(:, m))
        rows%worst_interior = max(rows%worst_interior, abs(row))
      end do
      rows%ghosts = rows%ghosts + nodes%n_ghost
      rows%interiors = rows%interiors + nodes%n_interior
    end associate
  end subroutine component_rows

  !> Each step, the box's momentum change equals dt (f L^3 - sum_b F_b) + sum_b (the momentum
  !> change of the fictitious fluid on body b's nodes) (test_immersed_stokes, here with CN).
  subroutine check_momentum_budget()
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(2)
    type(ibm_settings_t) :: settings
    real(wp), parameter :: drive(3) = [2.0_wp, -1.0_wp, 0.5_wp]   ! N/m^3
    real(wp) :: dt, before(3), after(3), expected(3), fictitious(3), worst, box
    integer :: step, n
    box = 1.0e-3_wp
    grid_cfg = grid_config_t(nx=16, ny=16, nz=16, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = 1000.0_wp
    fluid_cfg%viscosity = 1.0e-6_wp
    fluid_cfg%pressure_scheme = 'incremental'
    fluid_cfg%viscous_scheme = 'crank_nicolson'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    motion(1)%shape = make_spheroid('sphere', 0.2_wp * box, 1000.0_wp)
    motion(1)%centre = [0.3_wp, 0.45_wp, 0.5_wp] * box
    motion(1)%velocity = [2.0e-4_wp, 1.0e-4_wp, 0.0_wp]
    motion(1)%amplitude = [0.0_wp, 0.0_wp, 0.05_wp] * box
    motion(1)%frequency = 1.0_wp
    motion(2)%shape = make_spheroid('needle', 0.12_wp * box, 1000.0_wp, 2.0_wp)
    motion(2)%centre = [0.75_wp, 0.7_wp, 0.2_wp] * box
    motion(2)%orientation = [0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp] / norm2([0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp])
    motion(2)%angular_velocity = [0.0_wp, 0.4_wp, 0.2_wp]
    settings%coupling = 'implicit'
    settings%fluid_density = fluid_cfg%density
    ! At the default predictor_tolerance (1e-8) the budget closes to that order (the fluid rows'
    ! residual); at 1e-11 it closes to round-off level.
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, driving_force=drive, &
                               predictor_config=default_predictor_config(1.0e-11_wp, 200)))
    dt = 2.0_wp * solver%grid%dx**2 / fluid_cfg%viscosity
    worst = 0
    do step = 1, 10
      before = box_momentum(solver)
      call immersed_step(scene, solver, dt)
      fictitious = 0
      do n = 1, 2
        fictitious = fictitious + scene%ibm%inertia_change(1:3, n)
      end do
      after = box_momentum(solver)
      expected = dt * (drive * box**3 - sum(scene%force, dim=2)) + fictitious
      worst = max(worst, maxval(abs(after - before - expected)) / maxval(abs(after - before)))
    end do
    print '(a,es10.2,a,i0,a,i0,a)', 'crank_nicolson: momentum budget worst relative mismatch ', worst, &
        ', matrices built ', scene%predictor%builds, ' times (', scene%predictor%updates, &
        ' component matrices with the same structure: values replaced)'
    call check_below(worst, 1.0e-10_wp, 'crank_nicolson_momentum_budget_closes')
    call check(scene%predictor%builds == 10, 'moving_bodies_rebuild_every_step')
  end subroutine check_momentum_budget

  !> Two identical scenes with a fixed sphere step with dt, 1.7 dt, 0.6 dt: one replaces the
  !> Helmholtz values when dt changes, the other is told the nodes were reclassified and assembles
  !> its rows again. Same system, so the same loads.
  subroutine check_new_dt_same_as_rebuild()
    type(fluid_solver_t) :: solver(2)
    type(immersed_scene_t) :: scene(2)
    real(wp), parameter :: factors(3) = [1.0_wp, 1.7_wp, 0.6_wp]
    real(wp) :: dt, worst
    integer :: step
    call twin_sphere_scenes(solver, scene, [0.0_wp, 0.0_wp, 0.0_wp])
    worst = 0
    do step = 1, size(factors)
      dt = factors(step) * solver(1)%grid%dx**2 / solver(1)%viscosity
      call immersed_step(scene(1), solver(1), dt)
      call immersed_predictor_reclassified(scene(2)%predictor)
      call immersed_step(scene(2), solver(2), dt)
      worst = max(worst, maxval(abs(scene(1)%force - scene(2)%force)) / maxval(abs(scene(2)%force)))
    end do
    print '(a,es10.2,a,i0,a,i0)', 'new dt: loads against rebuilt matrices, worst relative difference ', worst, &
        '; builds ', scene(1)%predictor%builds, ' and ', scene(2)%predictor%builds
    call check_below(worst, 1.0e-9_wp, 'new_dt_updates_values_like_a_rebuild')
    call check(scene(1)%predictor%builds == 1 .and. scene(2)%predictor%builds == size(factors), &
               'new_dt_on_fixed_bodies_builds_once')
  end subroutine check_new_dt_same_as_rebuild

  !> Two identical scenes (16^3, water-like, Crank-Nicolson, incremental pressure, driven) with one
  !> implicit sphere moving cells_per_step(:) cells per step of dt = dx^2 / nu: the pairs of
  !> check_new_dt_same_as_rebuild and check_slow_body_same_as_creation.
  subroutine twin_sphere_scenes(solver, scene, cells_per_step, method)
    type(fluid_solver_t), intent(inout) :: solver(2)
    type(immersed_scene_t), intent(inout) :: scene(2)
    real(wp), intent(in) :: cells_per_step(3)
    character(len=*), intent(in), optional :: method   !< the predictor's method for both (default its own)
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(prescribed_motion_t) :: motion(1)
    type(ibm_settings_t) :: settings
    real(wp), parameter :: box = 1.0e-3_wp
    integer :: s
    grid_cfg = grid_config_t(nx=16, ny=16, nz=16, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = 1000.0_wp
    fluid_cfg%viscosity = 1.0e-6_wp
    fluid_cfg%pressure_scheme = 'incremental'
    fluid_cfg%viscous_scheme = 'crank_nicolson'
    motion(1)%shape = make_spheroid('sphere', 0.25_wp * box, 1000.0_wp)
    motion(1)%centre = [0.52_wp, 0.47_wp, 0.51_wp] * box
    ! dx / (dx^2 / nu) = nu / dx
    motion(1)%velocity = cells_per_step * fluid_cfg%viscosity / (box / 16)
    settings%coupling = 'implicit'
    settings%fluid_density = fluid_cfg%density
    do s = 1, 2
      call fluid_solver_create(solver(s), grid_cfg, fluid_cfg)
      solver(s)%u = 0; solver(s)%v = 0; solver(s)%w = 0; solver(s)%pressure = 0
      call immersed_scene_create(scene(s), solver(s), motion, immersed_scene_options_t(settings=settings, &
                                 driving_force=[2.0_wp, 0.5_wp, 0.0_wp], &
                                 predictor_config=default_predictor_config(1.0e-12_wp, 200)))
      if (present(method)) scene(s)%predictor%method = method
    end do
  end subroutine twin_sphere_scenes

  !> A sphere moving 0.01 cells per step (reclassified every step; most steps change no node's
  !> status): one scene replaces only the values when the rows keep their structure, the other
  !> creates its hypre solvers every step. Same systems, so the same loads.
  subroutine check_slow_body_same_as_creation()
    type(fluid_solver_t) :: solver(2)
    type(immersed_scene_t) :: scene(2)
    real(wp) :: dt, worst
    integer :: step, s
    call twin_sphere_scenes(solver, scene, [0.01_wp, 0.004_wp, 0.0_wp], 'hypre')
    dt = solver(1)%grid%dx**2 / solver(1)%viscosity
    scene(2)%predictor%reuse_structure = .false.
    worst = 0
    do step = 1, 8
      do s = 1, 2
        call immersed_step(scene(s), solver(s), dt)
      end do
      worst = max(worst, maxval(abs(scene(1)%force - scene(2)%force)) / maxval(abs(scene(2)%force)))
    end do
    print '(a,es10.2,a,i0,a)', 'slow body: loads against solvers created every step, worst relative difference ', &
        worst, ' (', scene(1)%predictor%updates, ' component matrices with only new values)'
    call check_below(worst, 1.0e-9_wp, 'slow_body_values_update_like_creation')
    call check(scene(1)%predictor%updates > 0 .and. scene(2)%predictor%updates == 0, 'slow_body_reuses_structure')
  end subroutine check_slow_body_same_as_creation

  !> The predictor builds a component matrix only when the body rows' pattern changed (a node
  !> changed status or a ghost row its stencil cell, as seen from the classification itself):
  !> 5 steps of a sphere creeping 1e-6 cells per step, then a step after a jump of half a cell.
  subroutine check_values_only_without_status_change()
    type(fluid_solver_t) :: solver(2)
    type(immersed_scene_t) :: scene(2)
    integer, allocatable :: before(:, :), after(:, :)
    integer :: step, builds, updates, unchanged_steps, wrong_steps
    real(wp) :: dx
    call twin_sphere_scenes(solver, scene, [1.0e-6_wp, 0.0_wp, 0.0_wp], 'hypre')
    dx = solver(1)%grid%dx
    call immersed_step(scene(1), solver(1), dx**2 / solver(1)%viscosity)
    call pattern_codes(scene(1), solver(1), before)
    unchanged_steps = 0
    wrong_steps = 0
    do step = 2, 6
      builds = scene(1)%predictor%full_builds
      updates = scene(1)%predictor%updates
      call immersed_step(scene(1), solver(1), dx**2 / solver(1)%viscosity)
      call pattern_codes(scene(1), solver(1), after)
      if (all(after == before)) then
        unchanged_steps = unchanged_steps + 1
        if (scene(1)%predictor%full_builds /= builds .or. scene(1)%predictor%updates /= updates + 3) &
            wrong_steps = wrong_steps + 1
      end if
      call move_alloc(after, before)
    end do
    print '(a,i0,a,i0,a,i0,a)', 'creeping sphere: ', unchanged_steps, ' of 5 steps without a pattern change, ', &
        scene(1)%predictor%full_builds, ' component matrices built, ', scene(1)%predictor%updates, ' values only'
    call check(unchanged_steps == 5, 'creeping_sphere_changes_no_node_status')
    call check(wrong_steps == 0 .and. scene(1)%predictor%full_builds == 3, 'values_only_steps_build_no_matrix')
    builds = scene(1)%predictor%full_builds
    scene(1)%motion(1)%centre = scene(1)%motion(1)%centre + [0.5_wp, 0.3_wp, 0.0_wp] * dx
    call immersed_step(scene(1), solver(1), dx**2 / solver(1)%viscosity)
    call pattern_codes(scene(1), solver(1), after)
    print '(a,i0,a)', 'after a jump of half a cell: ', scene(1)%predictor%full_builds - builds, ' component matrices built'
    call check(any(after /= before) .and. scene(1)%predictor%full_builds == builds + 3, &
               'status_change_builds_the_matrices')
  end subroutine check_values_only_without_status_change

  !> The default method (GMRES on the ghost rows, immersed_capacitance) against hypre's BiCGSTAB on
  !> the whole system (the reference), both to 1e-12: a sphere translating 0.05 cells per step
  !> (reclassified every step, nodes change status) at nu dt/dx^2 = 1, 6 steps. The same system, so
  !> the loads and the velocity field agree to the solves' tolerance (bound 1e-9 of the largest).
  subroutine check_capacitance_same_as_hypre()
    type(fluid_solver_t) :: solver(2)
    type(immersed_scene_t) :: scene(2)
    real(wp) :: dt, worst_load, worst_field, scale
    integer :: step, s
    call twin_sphere_scenes(solver, scene, [0.05_wp, 0.02_wp, -0.01_wp])
    scene(2)%predictor%method = 'hypre'
    dt = solver(1)%grid%dx**2 / solver(1)%viscosity
    worst_load = 0
    worst_field = 0
    do step = 1, 6
      do s = 1, 2
        call immersed_step(scene(s), solver(s), dt)
      end do
      worst_load = max(worst_load, maxval(abs(scene(1)%force - scene(2)%force)) / maxval(abs(scene(2)%force)))
      scale = max(maxval(abs(solver(2)%u)), maxval(abs(solver(2)%v)), maxval(abs(solver(2)%w)))
      worst_field = max(worst_field, max(maxval(abs(solver(1)%u - solver(2)%u)), maxval(abs(solver(1)%v - solver(2)%v)), &
                                         maxval(abs(solver(1)%w - solver(2)%w))) / scale)
    end do
    print '(a,es10.2,a,es10.2,a,i0,a,i0,a)', 'capacitance against hypre: loads ', worst_load, ', velocity ', &
        worst_field, ' (relative); FFT solves ', scene(1)%predictor%fft_solves, ' over ', 3 * 6, ' component solves'
    call check_below(worst_load, 1.0e-9_wp, 'capacitance_loads_equal_hypre')
    call check_below(worst_field, 1.0e-9_wp, 'capacitance_velocity_equals_hypre')
    call check_preconditioner_matrix(scene(1))
  end subroutine check_capacitance_same_as_hypre

  !> The preconditioner's sparse C~ (capacitance_preconditioner) against the capacitance matrix
  !> C = A_G H^{-1} P_G^T formed column by column with the FFT solve (the last component solved,
  !> w, one rank): C - C~ holds only the terms g(x_a - x_H) with the offset outside the window, so
  !> |C - C~|_{GH} <= sum_a |A_Ga| max_{outside} |g|, with g = H^{-1} e_0 from the same FFT solve.
  subroutine check_preconditioner_matrix(scene)
    type(immersed_scene_t), intent(inout) :: scene
    real(wp), allocatable :: unit(:), image(:), exact(:, :), sparse(:, :), weight_sum(:)
    real(wp) :: outside, worst_ratio, largest_difference
    integer :: ng, g, h, corner, position, i, j, k, n_rows, reach(3)
    associate (grid => scene%predictor%grid, nodes => scene%ibm%geometry%component(3), &
               pre => scene%predictor%reduced%preconditioner, sys => scene%predictor%system(3))
      ng = nodes%n_ghost
      n_rows = grid%nx * grid%ny * grid%nz_local
      reach = pre%reach
      allocate(unit(n_rows), image(n_rows), exact(ng, ng), sparse(ng, ng), weight_sum(ng))
      ! max |g| over the offsets outside the window
      unit = 0
      unit(1) = 1
      call scene%predictor%inverse%apply(unit, image)
      outside = 0
      do k = 1, grid%nz
        do j = 1, grid%ny
          do i = 1, grid%nx
            if (all(abs(wrapped_offset([i, j, k], [grid%nx, grid%ny, grid%nz])) <= reach)) cycle
            outside = max(outside, abs(image(i + grid%nx * ((j - 1) + grid%ny * (k - 1)))))
          end do
        end do
      end do
      do h = 1, ng
        unit = 0
        unit(sys%ghost_rows(h)) = 1
        call scene%predictor%inverse%apply(unit, image)
        image(sys%interior_rows) = 0
        do g = 1, ng
          associate (ghost => nodes%ghost(g))
            exact(g, h) = ghost_row_diagonal(ghost) * image(sys%ghost_rows(g))
            weight_sum(g) = abs(ghost_row_diagonal(ghost))
            do corner = 1, 8
              if (corner == ghost%self_corner) cycle
              exact(g, h) = exact(g, h) + ghost%extrapolation * ghost%weight(corner) * &
                            image(ghost%stencil(1, corner) + grid%nx * ((ghost%stencil(2, corner) - 1) + &
                                  grid%ny * (ghost%stencil(3, corner) - 1)))
              weight_sum(g) = weight_sum(g) + abs(ghost%extrapolation * ghost%weight(corner))
            end do
          end associate
        end do
      end do
      sparse = 0
      do g = 1, ng
        do position = pre%row_start(g), pre%row_start(g + 1) - 1
          sparse(g, pre%column(position)) = pre%entry(position)
        end do
      end do
      worst_ratio = 0
      do g = 1, ng
        worst_ratio = max(worst_ratio, maxval(abs(exact(g, :) - sparse(g, :))) / (weight_sum(g) * outside))
      end do
      largest_difference = maxval(abs(exact - sparse)) / maxval(abs(exact))
    end associate
    print '(a,3(i0,1x),a,es10.2,a,f6.3,a,es10.2,a)', 'local capacitance matrix: window ', reach, &
        'cells, |g| outside ', outside, '; |C - C~| / bound ', worst_ratio, ' (largest ', largest_difference, ' of max |C|)'
    call check_below(worst_ratio, 1.0_wp + 1.0e-9_wp, 'local_capacitance_within_truncation_bound')
    call check_below(largest_difference, 1.0e-2_wp, 'local_capacitance_close_to_capacitance')
  end subroutine check_preconditioner_matrix

  !> The periodic offset of node (1-based) from node 1, in -(n-1)/2 .. n/2 per direction.
  pure function wrapped_offset(node, n) result(offset)
    integer, intent(in) :: node(3), n(3)
    integer :: offset(3)
    offset = modulo(node - 1 + n / 2, n) - n / 2
  end function wrapped_offset

  !> One code per node and component (one rank: local = global planes): 0 fluid, -1 interior,
  !> for a ghost 1 + the global row of its stencil's first corner (the cell of its image point).
  subroutine pattern_codes(scene, solver, codes)
    type(immersed_scene_t), intent(in) :: scene
    type(fluid_solver_t), intent(in) :: solver
    integer, allocatable, intent(out) :: codes(:, :)
    integer :: c, g, m, n(3)
    n = [solver%grid%nx, solver%grid%ny, solver%grid%nz_local]
    allocate(codes(product(n), 3), source=0)
    do c = 1, 3
      associate (nodes => scene%ibm%geometry%component(c))
        do g = 1, nodes%n_ghost
          associate (ghost => nodes%ghost(g))
            codes(node_row(n, ghost%node), c) = 1 + node_row(n, ghost%stencil(:, 1))
          end associate
        end do
        do m = 1, nodes%n_interior
          codes(node_row(n, nodes%interior(:, m)), c) = -1
        end do
      end associate
    end do
  end subroutine pattern_codes

  !> Row of node (i, j, k) among n(1) x n(2) x n(3) nodes, x fastest.
  pure integer function node_row(n, node)
    integer, intent(in) :: n(3), node(3)
    node_row = node(1) + n(1) * ((node(2) - 1) + n(2) * (node(3) - 1))
  end function node_row

  !> Total fluid momentum rho dV sum u of the box (kg m/s), every node of every component.
  function box_momentum(solver) result(p)
    type(fluid_solver_t), intent(in) :: solver
    real(wp) :: p(3)
    integer :: nx, ny, nzl
    nx = solver%grid%nx; ny = solver%grid%ny; nzl = solver%grid%nz_local
    p = solver%density * solver%grid%cell_volume * &
        [global_sum(sum(solver%u(1:nx, 1:ny, 1:nzl))), global_sum(sum(solver%v(1:nx, 1:ny, 1:nzl))), &
         global_sum(sum(solver%w(1:nx, 1:ny, 1:nzl)))]
  end function box_momentum
end program test_immersed_cn
