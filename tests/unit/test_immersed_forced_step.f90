! checks: 3
!> The body force of a forced box with immersed bodies (immersed_step with fluid_force_*, as the
!> resolved scene passes the Eswaran-Pope f^n; docs/decks.md, &forcing): the predictor's force is
!> the uniform drive plus the fluid force on the fluid nodes of the step's placement, and the drive
!> alone on the bodies' ghost and interior nodes (the imposition replaces them; a fluid force there
!> would only add rho f over the body's nodes to its load). One fixed sphere and one translating
!> needle at 16^3, one step: every node of u, v and w checked against its status.
program test_immersed_forced_step
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use config_grid, only: grid_config_t
  use config_fluid, only: fluid_config_t
  use fluid_solver, only: fluid_solver_t, fluid_solver_create
  use fluid_grid, only: allocate_field
  use spheroid, only: make_spheroid
  use immersed_geometry, only: node_fluid
  use immersed_boundary, only: ibm_settings_t
  use immersed_scene, only: prescribed_motion_t, immersed_scene_t, immersed_scene_options_t, immersed_scene_create, immersed_step
  use test_framework, only: test_start, test_finish, check_below, check_above
  implicit none
  real(wp), parameter :: density = 997.0_wp, drive(3) = [5.0_wp, 0.0_wp, -2.0_wp]   ! N/m^3
  real(wp), parameter :: fluid_force(3) = [0.3_wp, -0.2_wp, 0.1_wp]                    ! m/s^2
  type(fluid_solver_t) :: solver
  type(immersed_scene_t) :: scene
  type(prescribed_motion_t) :: motion(2)
  type(ibm_settings_t) :: settings
  real(wp), allocatable :: fx(:, :, :), fy(:, :, :), fz(:, :, :)
  real(wp) :: worst_fluid, worst_body, dx
  integer :: fluid_nodes, body_nodes

  call parallel_start()
  call test_start('immersed_forced_step')
  call fluid_solver_create(solver, grid_config_t(nx=16, ny=16, nz=16, length_x=1.0e-3_wp, length_y=1.0e-3_wp, &
                                                 length_z=1.0e-3_wp), &
                           fluid_config_t(viscosity=1.0e-6_wp, density=density, viscous_scheme='explicit'))
  dx = solver%grid%dx
  motion(1)%shape = make_spheroid('sphere', 3.0_wp * dx, 1.0_wp)
  motion(1)%centre = [0.3e-3_wp, 0.4e-3_wp, 0.45e-3_wp]
  motion(2)%shape = make_spheroid('needle', 3.0_wp * dx, 1.0_wp, 2.0_wp)
  motion(2)%centre = [0.7e-3_wp, 0.65e-3_wp, 0.8e-3_wp]
  motion(2)%velocity = [2.0e-3_wp, 0.0_wp, 1.0e-3_wp]
  settings%fluid_density = density
  call immersed_scene_create(scene, solver, motion, immersed_scene_options_t(settings=settings, driving_force=drive))
  call allocate_field(solver%grid, fx); call allocate_field(solver%grid, fy); call allocate_field(solver%grid, fz)
  fx = fluid_force(1); fy = fluid_force(2); fz = fluid_force(3)
  call immersed_step(scene, solver, 1.0e-5_wp, fx, fy, fz)

  worst_fluid = 0; worst_body = 0; fluid_nodes = 0; body_nodes = 0
  call check_component(1, scene%force_u)
  call check_component(2, scene%force_v)
  call check_component(3, scene%force_w)
  write(*, '(a,i0,a,i0)') 'fluid nodes ', fluid_nodes, ', body nodes ', body_nodes
  call check_below(worst_fluid, 1.0e-14_wp, 'fluid_nodes_take_drive_and_fluid_force')
  call check_below(worst_body, 1.0e-14_wp, 'body_nodes_take_the_drive_only')
  call check_above(real(body_nodes, wp), 100.0_wp, 'bodies_cover_nodes')
  call test_finish()

contains

  !> Largest deviation (relative to |f| + |drive/rho|) of the predictor force of component c from
  !> drive/rho + f (fluid nodes) or drive/rho (ghost and interior nodes), over this rank's nodes.
  subroutine check_component(c, force)
    integer, intent(in) :: c
    real(wp), intent(in) :: force(0:, 0:, 0:)
    real(wp) :: scale
    integer :: i, j, k
    scale = abs(fluid_force(c)) + abs(drive(c)) / density
    do k = 1, solver%grid%nz_local
      do j = 1, solver%grid%ny
        do i = 1, solver%grid%nx
          if (scene%ibm%geometry%component(c)%status(i, j, k) == node_fluid) then
            worst_fluid = max(worst_fluid, abs(force(i, j, k) - drive(c) / density - fluid_force(c)) / scale)
            fluid_nodes = fluid_nodes + 1
          else
            worst_body = max(worst_body, abs(force(i, j, k) - drive(c) / density) / scale)
            body_nodes = body_nodes + 1
          end if
        end do
      end do
    end do
  end subroutine check_component
end program test_immersed_forced_step
