!> The stop of a run whose CFL time step has collapsed (&run dt_mode = 'cfl'): the step the run
!> would take is far below the largest it allows, or so small that end_time is out of reach. Either
!> way the flow has blown up (or the initial field is far too fast for the grid) and the run would
!> crawl on for ever; it stops with the CFL number, the fastest velocity component and where it is.
!> Called by every time loop of the resolved fluid with the field's advective rate before each step.
module time_step_guard
  use agglo_kinds, only: wp, i8
  use mpi_f08, only: MPI_Allreduce, MPI_Bcast, MPI_IN_PLACE, MPI_MAXLOC, MPI_2DOUBLE_PRECISION
  use parallel_env, only: world, mpi_wp, my_rank
  use config_run, only: run_config_t, step_count_limit
  use error_handling, only: fatal
  use text_format, only: real_text, int_text
  use fluid_grid, only: x_centre, y_centre, z_centre, x_face, y_face, z_face
  use fluid_solver, only: fluid_solver_t
  use time_step_control, only: next_time_step, explicit_viscous_limit
  implicit none
  private
  public :: check_time_step, collapse_factor

  !> The CFL step has collapsed when it is below this fraction of the largest step the run allows,
  !> min(&run dt, cfl_target x the explicit-diffusion limit): a velocity 10^6 times the one at
  !> which the CFL step reaches that cap is no flow the grid resolves.
  real(wp), parameter :: collapse_factor = 1.0e-6_wp

  !> The fastest velocity component of the field (largest |u_d| / dx_d): its value, component and
  !> place (global indices of its MAC-grid node and its position).
  type :: fastest_node_t
    real(wp) :: velocity = 0.0_wp     !< m/s, signed
    integer :: component = 1          !< 1 = u, 2 = v, 3 = w
    integer :: index(3) = 0           !< i, j, k (global, 1-based)
    real(wp) :: position(3) = 0.0_wp  !< m
  end type fastest_node_t

contains

  !> With dt_mode = 'cfl': stop the run (every rank together; rate is the global advective rate
  !> sum_d max|u_d|/dx_d of the current field) if the CFL step is below collapse_factor x the
  !> largest step, or if (end_time - time) / step exceeds step_count_limit (&run max_steps, at
  !> least 1e9), the limit the deck's own dt is held to before the run. Fixed steps are checked
  !> before the run (config_run) and by the CFL limit after each step.
  subroutine check_time_step(run, solver, rate)
    type(run_config_t), intent(in) :: run
    type(fluid_solver_t), intent(in) :: solver
    real(wp), intent(in) :: rate
    real(wp) :: viscous_limit, largest, dt, steps_left
    character(len=:), allocatable :: reason
    if (run%dt_mode /= 'cfl') return
    viscous_limit = huge(1.0_wp)
    if (.not. solver%crank_nicolson) viscous_limit = explicit_viscous_limit(solver%grid%dx, solver%grid%dy, &
                                                                            solver%grid%dz, solver%viscosity)
    largest = min(run%dt, run%cfl_target * viscous_limit)
    ! The step of this field without the shortening of the last step before end_time.
    dt = next_time_step('cfl', run%dt, run%cfl_target, rate, viscous_limit, 0.0_wp, huge(1.0_wp))
    steps_left = (run%end_time - solver%time) / dt
    if (dt < collapse_factor * largest) then
      reason = 'dt = '//real_text(dt)//' s is below '//real_text(collapse_factor)//' x the largest step '// &
               real_text(largest)//' s, min(&run dt, cfl_target x explicit-diffusion limit)'
    else if (steps_left > step_count_limit(run) * (1.0_wp + 1.0e-9_wp)) then
      reason = 'dt = '//real_text(dt)//' s leaves (end_time - t) / dt = '//real_text(steps_left)// &
               ' steps to &run end_time = '//real_text(run%end_time)//' s, more than '// &
               int_text(int(step_count_limit(run), i8))//', max(max_steps, 1e9)'
    else
      return
    end if
    call fatal('time step: the CFL step has collapsed at step '//int_text(solver%step)//' (t = '// &
        real_text(solver%time)//' s): '//reason//'; CFL number '//real_text(dt * rate)//' with '// &
        fastest_text(fastest_node(solver))//'; the flow has blown up, or the initial field (&fluid init_amplitude, '// &
        'init_file) is far too fast for &grid')
  end subroutine check_time_step

  !> The node of the largest |u_d| / dx_d over the whole field (collective: every rank gets it).
  function fastest_node(solver) result(node)
    type(fluid_solver_t), intent(in) :: solver
    type(fastest_node_t) :: node
    real(wp) :: best(2), spacing(3), speed, shared(5)
    integer :: i, j, k, d
    spacing = [solver%grid%dx, solver%grid%dy, solver%grid%dz]
    best = [-1.0_wp, real(my_rank, wp)]
    do d = 1, 3
      do k = 1, solver%grid%nz_local
        do j = 1, solver%grid%ny
          do i = 1, solver%grid%nx
            speed = component_value(solver, d, i, j, k)
            if (abs(speed) / spacing(d) > best(1)) then
              best(1) = abs(speed) / spacing(d)
              node%velocity = speed
              node%component = d
              node%index = [i, j, k]
            end if
          end do
        end do
      end do
    end do
    ! Positions from the local k (fluid_grid's z functions add the slab offset), then the global k.
    select case (node%component)
    case (1)
      node%position = [x_face(solver%grid, node%index(1)), y_centre(solver%grid, node%index(2)), &
                       z_centre(solver%grid, node%index(3))]
    case (2)
      node%position = [x_centre(solver%grid, node%index(1)), y_face(solver%grid, node%index(2)), &
                       z_centre(solver%grid, node%index(3))]
    case default
      node%position = [x_centre(solver%grid, node%index(1)), y_centre(solver%grid, node%index(2)), &
                       z_face(solver%grid, node%index(3))]
    end select
    node%index(3) = node%index(3) + solver%grid%z_offset
    ! The rank holding the largest value (the lowest such rank) tells the others its node.
    call MPI_Allreduce(MPI_IN_PLACE, best, 1, MPI_2DOUBLE_PRECISION, MPI_MAXLOC, world)
    shared = [node%velocity, real(node%component, wp), real(node%index, wp)]
    call MPI_Bcast(shared, 5, mpi_wp, nint(best(2)), world)
    call MPI_Bcast(node%position, 3, mpi_wp, nint(best(2)), world)
    node%velocity = shared(1)
    node%component = nint(shared(2))
    node%index = nint(shared(3:5))
  end function fastest_node

  pure real(wp) function component_value(solver, d, i, j, k)
    type(fluid_solver_t), intent(in) :: solver
    integer, intent(in) :: d, i, j, k
    select case (d)
    case (1)
      component_value = solver%u(i, j, k)
    case (2)
      component_value = solver%v(i, j, k)
    case default
      component_value = solver%w(i, j, k)
    end select
  end function component_value

  !> "the fastest velocity component v = -3.2E+30 m/s at v(3, 14, 7), position (1.6E-04, 8.8E-04, 4.1E-04) m"
  function fastest_text(node) result(text)
    type(fastest_node_t), intent(in) :: node
    character(len=:), allocatable :: text
    character(len=1), parameter :: names(3) = ['u', 'v', 'w']
    text = 'the fastest velocity component '//names(node%component)//' = '//real_text(node%velocity)//' m/s at '// &
           names(node%component)//'('//int_text(node%index(1))//', '//int_text(node%index(2))//', '// &
           int_text(node%index(3))//') of &grid, position ('//real_text(node%position(1))//', '// &
           real_text(node%position(2))//', '//real_text(node%position(3))//') m'
  end function fastest_text
end module time_step_guard
