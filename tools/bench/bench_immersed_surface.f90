!> The immersed boundary's surface loads and mesh geometry (make validate; docs/studies/validation.md,
!> "Surface loads and mesh geometry"):
!> 1. rung 5 of the validation ladder: the face-sum load (load_method = 'surface', icosphere of 80,
!>    320 and 1280 faces) against the momentum-balance load on the steady simple-cubic sphere array
!>    at phi = 0.125, D/dx about 8, 12 and 16 (bound: 5% at D/dx = 16), and the same for the torque
!>    of a rotating sphere (L/D = 2, no drive, 320 faces) at D/dx = 8, 12 and 16;
!> 2. the drag coefficient K of the sphere array with the ghost nodes' closest points from the
!>    icosphere ('mesh' geometry, 80/320/1280 faces) against the analytic sphere, D/dx about 8 and 12,
!>    and against Zick & Homsy (1982, J. Fluid Mech. 115, 13, Table 2: K = 4.292 at phi = 0.125).
!> Prints Markdown tables.
program bench_immersed_surface
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  implicit none
  real(wp), parameter :: zick_homsy = 4.292_wp
  integer, parameter :: array_cells(3) = [13, 19, 26], rotating_cells(3) = [16, 24, 32], levels(3) = [1, 2, 3]
  type(sphere_array_case_t) :: case
  type(sphere_array_result_t) :: result
  real(wp) :: analytic_k
  integer :: d, l

  call parallel_start()
  if (is_root()) then
    print '(a)', '| case | cells | D/dx | faces | momentum | face sum | difference | steps | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|'
  end if
  do d = 1, size(array_cells)
    do l = 1, size(levels)
      case = sphere_array_case_t(cells=array_cells(d), volume_fraction=0.125_wp, surface_level=levels(l), &
                                 max_steps=60000)
      call run_sphere_array(case, result)
      call print_row('array F_x', result%force(1), result%surface_force(1))
    end do
  end do
  do d = 1, size(rotating_cells)
    case = sphere_array_case_t(cells=rotating_cells(d), volume_fraction=acos(-1.0_wp) / 48.0_wp, rotating=.true., &
                               surface_level=2, max_steps=60000)
    call run_sphere_array(case, result)
    call print_row('rotating T_z', result%torque(3), result%surface_torque(3))
  end do

  if (is_root()) then
    print '(a)', ''
    print '(a)', '| cells | D/dx | geometry | faces | K | K error (Z&H) | K - K(analytic) | steps | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|'
  end if
  do d = 1, 2
    analytic_k = 0
    do l = 0, size(levels)
      case = sphere_array_case_t(cells=array_cells(d), volume_fraction=0.125_wp, max_steps=60000)
      if (l > 0) case%mesh_level = levels(l)
      call run_sphere_array(case, result)
      if (l == 0) analytic_k = result%drag_coefficient
      if (is_root()) print '(a,i0,a,f5.2,a,a,a,a,a,f6.4,a,f7.2,a,f7.2,a,i0,a,f6.1,a,a)', '| ', case%cells, '^3 | ', &
          result%diameter_cells, ' | ', merge('mesh    ', 'analytic', l > 0), ' | ', trim(face_text(l)), ' | ', &
          result%drag_coefficient, ' | ', 100 * (result%drag_coefficient / zick_homsy - 1), '% | ', &
          100 * (result%drag_coefficient / analytic_k - 1), '% | ', result%steps, ' | ', result%wall_seconds, &
          merge(' |         ', ' unsteady |', result%steady)
    end do
  end do
  call parallel_stop()

contains

  subroutine print_row(name, momentum, surface)
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: momentum, surface
    if (is_root()) print '(a,a,a,i0,a,f5.2,a,i0,a,es11.4,a,es11.4,a,f7.2,a,i0,a,f6.1,a,a)', '| ', name, ' | ', &
        case%cells, '^3 | ', result%diameter_cells, ' | ', 20 * 4**case%surface_level, ' | ', momentum, ' | ', surface, &
        ' | ', 100 * (surface / momentum - 1), '% | ', result%steps, ' | ', result%wall_seconds, &
        merge(' |         ', ' unsteady |', result%steady)
  end subroutine print_row

  function face_text(level_index) result(text)
    integer, intent(in) :: level_index
    character(len=8) :: text
    text = '-'
    if (level_index > 0) write(text, '(i0)') 20 * 4**levels(level_index)
  end function face_text
end program bench_immersed_surface
