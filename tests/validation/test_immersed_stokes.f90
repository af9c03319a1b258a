! checks: 11
!> The immersed boundary in Stokes flow (docs/studies/validation.md, rungs 2, 4 and 5):
!> - simple-cubic sphere array at phi = 0.125, D/dx = 8.06 (13^3): K against Zick & Homsy (1982,
!>   J. Fluid Mech. 115, 13, Table 2) K = 4.292, within 5% (implicit) and 11% (explicit);
!> - ghost rows converge in at most 10 Jacobi sweeps to 1e-12 (rung 2);
!> - at steady state the momentum-balance load equals the drive on the cell, F = f L^3 (the fluid
!>   momentum no longer changes);
!> - the global momentum budget of the box, P^{n+1} - P^n = dt (f L^3 - sum of the body forces) +
!>   the fictitious fluid's momentum change on the bodies' nodes, closes to 1e-10 relative over steps
!>   of a translating, oscillating sphere and a rotating needle (nodes change status) in a driven,
!>   non-steady flow.
program test_immersed_stokes
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, global_sum
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use spheroid, only: make_spheroid
  use immersed_boundary, only: ibm_settings_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp   ! Zick & Homsy 1982, Table 2, phi = 0.125
  type(sphere_array_case_t) :: case
  type(sphere_array_result_t) :: result
  character(len=120) :: text

  call parallel_start()
  call test_start('immersed_stokes')

  case%cells = 13
  case%volume_fraction = 0.125_wp
  case%coupling = 'implicit'
  call run_sphere_array(case, result)
  write(text, '(a,f6.2,a,f7.4,a,f7.3,a,i0,a,f5.2,a,i0)') 'D/dx ', result%diameter_cells, ' K ', &
      result%drag_coefficient, ' error ', 100 * (result%drag_coefficient / zick_homsy_0125 - 1), '% steps ', &
      result%steps, ' sweeps mean ', result%mean_sweeps, ' max ', result%max_sweeps
  print '(a)', 'implicit: '//trim(text)
  call check(result%steady, 'implicit_reaches_steady_state')
  call check_close(result%drag_coefficient, zick_homsy_0125, 0.05_wp, 'implicit_drag_zick_homsy_5pc')
  call check_below(real(result%max_sweeps, wp), 10.0_wp, 'implicit_sweeps_at_most_10')
  call check_close(result%force(1), result%drive(1), 1.0e-6_wp, 'steady_load_equals_drive')
  call check_below(abs(result%force(2)) + abs(result%force(3)), 1.0e-6_wp * result%drive(1), &
                   'steady_load_along_drive')

  case%coupling = 'explicit'
  call run_sphere_array(case, result)
  write(text, '(a,f6.2,a,f7.4,a,f7.3,a,i0)') 'D/dx ', result%diameter_cells, ' K ', &
      result%drag_coefficient, ' error ', 100 * (result%drag_coefficient / zick_homsy_0125 - 1), '% steps ', &
      result%steps
  print '(a)', 'explicit: '//trim(text)
  call check(result%steady, 'explicit_reaches_steady_state')
  call check_close(result%drag_coefficient, zick_homsy_0125, 0.11_wp, 'explicit_drag_zick_homsy_11pc')

  call check_momentum_budget('implicit')
  call check_momentum_budget('explicit')
  call test_finish()

contains

  !> A sphere translating and oscillating and a rotating needle in a driven flow that starts from
  !> rest: each step, the box's momentum change equals dt (f L^3 - sum_b F_b) + sum_b (the momentum
  !> change of the fictitious fluid on body b's nodes).
  subroutine check_momentum_budget(coupling)
    character(len=*), intent(in) :: coupling
    type(grid_config_t) :: grid_cfg
    type(fluid_config_t) :: fluid_cfg
    type(fluid_solver_t) :: solver
    type(immersed_scene_t) :: scene
    type(prescribed_motion_t) :: motion(2)
    type(ibm_settings_t) :: settings
    real(wp), parameter :: drive(3) = [2.0_wp, -1.0_wp, 0.5_wp]   ! N/m^3
    real(wp) :: dt, before(3), after(3), expected(3), fictitious(3), worst, box
    integer :: step, n, changes
    box = 1.0e-3_wp
    grid_cfg = grid_config_t(nx=16, ny=16, nz=16, length_x=box, length_y=box, length_z=box)
    fluid_cfg%density = 1000.0_wp
    fluid_cfg%viscosity = 1.0e-6_wp
    fluid_cfg%pressure_scheme = 'incremental'
    call fluid_solver_create(solver, grid_cfg, fluid_cfg)
    solver%u = 0; solver%v = 0; solver%w = 0; solver%pressure = 0
    motion(1)%shape = make_spheroid('sphere', 0.2_wp * box, 1000.0_wp)
    motion(1)%centre = [0.3_wp, 0.45_wp, 0.5_wp] * box
    motion(1)%velocity = [1.0e-2_wp, 0.5e-2_wp, 0.0_wp]
    motion(1)%amplitude = [0.0_wp, 0.0_wp, 0.05_wp] * box
    motion(1)%frequency = 50.0_wp
    motion(2)%shape = make_spheroid('needle', 0.12_wp * box, 1000.0_wp, 2.0_wp)
    motion(2)%centre = [0.75_wp, 0.7_wp, 0.2_wp] * box
    motion(2)%orientation = [0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp] / norm2([0.9_wp, 0.1_wp, 0.3_wp, 0.3_wp])
    motion(2)%angular_velocity = [0.0_wp, 20.0_wp, 10.0_wp]
    settings%coupling = coupling
    settings%fluid_density = fluid_cfg%density
    call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, driving_force=drive))
    dt = 0.1_wp * solver%grid%dx**2 / fluid_cfg%viscosity
    worst = 0
    changes = 0
    do step = 1, 40
      before = box_momentum(solver)
      call immersed_step(scene, solver, dt)
      fictitious = 0
      do n = 1, 2
        fictitious = fictitious + scene%ibm%inertia_change(1:3, n)
      end do
      after = box_momentum(solver)
      expected = dt * (drive * box**3 - sum(scene%force, dim=2)) + fictitious
      worst = max(worst, maxval(abs(after - before - expected)) / maxval(abs(after - before)))
      if (scene%predicted%largest_change > 0) changes = changes + 1
    end do
    print '(a,es10.2)', coupling//': momentum budget worst relative mismatch ', worst
    call check_below(worst, 1.0e-10_wp, coupling//'_momentum_budget_closes')
    call check(changes == 40, coupling//'_impositions_change_the_field')
  end subroutine check_momentum_budget

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
end program test_immersed_stokes
