!> The immersed-boundary validation ladder (make validate; docs/validation.md, "Immersed boundary"):
!> simple-cubic sphere arrays in Stokes flow at D/dx about 8, 12 and 16, for phi = 0.125 and 0.064,
!> implicit and explicit coupling, against Zick & Homsy (1982, J. Fluid Mech. 115, 13, Table 2:
!> K = 4.292 at phi = 0.125, 2.810 at phi = 0.064), with the observed order of convergence between
!> the coarsest and the finest grid, p = ln(e_8 / e_16) / ln(D_16 / D_8). Then a rotating sphere at
!> D/dx = 8 and 12 in boxes L/D = 2, 3, 4: the torque -T (it opposes the rotation) extrapolated to
!> the unbounded box by a least-squares line in (a/L)^3 against 8 pi mu a^3 Omega (Stokes).
!> Prints Markdown tables.
program bench_immersed_ladder
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  implicit none
  real(wp), parameter :: fractions(2) = [0.125_wp, 0.064_wp], references(2) = [4.292_wp, 2.810_wp]
  real(wp), parameter :: diameters(3) = [8.0_wp, 12.0_wp, 16.0_wp]
  character(len=8), parameter :: couplings(2) = [character(len=8) :: 'implicit', 'explicit']
  type(sphere_array_case_t) :: case
  type(sphere_array_result_t) :: result
  real(wp) :: errors(3), sizes(3), x(3), y(3), slope, unbounded
  integer :: f, c, d, resolution

  call parallel_start()
  if (is_root()) then
    print '(a)', '| phi | coupling | cells | D/dx | K | K (Z&H) | error | steps | sweeps mean/max | slip | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|'
  end if
  do f = 1, size(fractions)
    do c = 1, size(couplings)
      do d = 1, size(diameters)
        case%volume_fraction = fractions(f)
        case%coupling = couplings(c)
        case%cells = nint(diameters(d) / (6.0_wp * fractions(f) / acos(-1.0_wp))**(1.0_wp / 3.0_wp))
        case%max_steps = 60000
        call run_sphere_array(case, result)
        errors(d) = result%drag_coefficient / references(f) - 1.0_wp
        sizes(d) = result%diameter_cells
        if (is_root()) print '(a,f5.3,a,a,a,i0,a,f5.2,a,f6.4,a,f5.3,a,f7.2,a,i0,a,f4.1,a,i0,a,es8.1,a,f6.1,a,a)', &
            '| ', fractions(f), ' | ', trim(couplings(c)), ' | ', case%cells, '^3 | ', result%diameter_cells, ' | ', &
            result%drag_coefficient, ' | ', references(f), ' | ', 100 * errors(d), '% | ', result%steps, ' | ', &
            result%mean_sweeps, '/', result%max_sweeps, ' | ', result%slip, ' | ', result%wall_seconds, &
            merge(' |         ', ' unsteady |', result%steady)
      end do
      if (is_root()) print '(a,f5.3,a,a,a,f5.2)', '|   | observed order, phi = ', fractions(f), ', ', trim(couplings(c)), &
          ': ', log(abs(errors(1)) / abs(errors(3))) / log(sizes(3) / sizes(1))
    end do
  end do
  if (is_root()) then
    print '(a)', ''
    print '(a)', '| coupling | cells | D/dx | a/L | T / (8 pi mu a^3 Omega) | steps | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|'
  end if
  do resolution = 8, 12, 4
  do c = 1, size(couplings)
    do d = 1, 3
      case%rotating = .true.
      case%coupling = couplings(c)
      case%cells = resolution * (d + 1)
      case%volume_fraction = acos(-1.0_wp) / 6.0_wp / real(d + 1, wp)**3
      call run_sphere_array(case, result)
      x(d) = result%radius_over_box**3
      y(d) = -result%torque(3) / result%stokes_torque
      if (is_root()) print '(a,a,a,i0,a,f5.2,a,f6.4,a,f8.5,a,i0,a,f6.1,a,a)', '| ', trim(couplings(c)), ' | ', &
          case%cells, '^3 | ', result%diameter_cells, ' | ', result%radius_over_box, ' | ', y(d), ' | ', result%steps, &
          ' | ', result%wall_seconds, merge(' |         ', ' unsteady |', result%steady)
    end do
    slope = (sum(x * y) - sum(x) * sum(y) / 3) / (sum(x**2) - sum(x)**2 / 3)
    unbounded = (sum(y) - slope * sum(x)) / 3
    if (is_root()) print '(a,a,a,f8.5,a,f7.2,a)', '|   | ', trim(couplings(c)), ': extrapolated to a/L = 0: ', unbounded, &
        ' (error ', 100 * (unbounded - 1), '%)'
  end do
  end do
  call parallel_stop()
end program bench_immersed_ladder
