!> Crank-Nicolson with free particles (docs/studies/validation.md, "Crank-Nicolson with free particles"):
!> the settling sphere of module settling_sphere_case (13^3, D/dx 8.06, phi = 0.125, calcite density
!> ratio) with explicit diffusion at nu dt/dx^2 = 0.06 and with Crank-Nicolson + hypre at
!> nu dt/dx^2 = 1, 5, 10 (4 and 40 particle sub-steps), and 1500 steps at 10, against Zick & Homsy
!> (1982, J. Fluid Mech. 115, 13, Table 2) K = 4.292.
program bench_free_cn
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use settling_sphere_case, only: settling_case_t, settling_result_t, run_settling_sphere
  implicit none
  real(wp), parameter :: zick_homsy = 4.292_wp
  real(wp), parameter :: numbers(4) = [0.06_wp, 1.0_wp, 5.0_wp, 10.0_wp]
  type(settling_case_t) :: case
  type(settling_result_t) :: result, explicit
  integer :: k, substeps
  call parallel_start()
  if (is_root()) then
    print '(a)', '| scheme | nu dt/dx^2 | sub-steps | K | vs Z&H | vs explicit | momentum | steady | steps | '// &
                 'wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|---|'
  end if
  do k = 1, size(numbers)
    do substeps = 4, 40, 36
      if (k == 1 .and. substeps > 4) cycle
      ! Crank-Nicolson's hypre tolerance (1e-8) leaves step-to-step noise of that order in the slip
      ! vector, so its steady stop is 1e-7 per step; explicit diffusion stops at the case's 1e-8.
      case = settling_case_t(viscous_number=numbers(k), substeps=substeps, max_steps=4000, &
                             viscous_scheme=merge('explicit      ', 'crank_nicolson', k == 1), &
                             steady_tolerance=merge(1.0e-8_wp, 1.0e-7_wp, k == 1))
      call run_settling_sphere(case, result)
      if (k == 1) explicit = result
      if (is_root()) print '(a,a,f5.2,a,i0,a,f7.4,a,f6.2,a,f7.3,a,es9.2,a,a,a,i0,a,f7.1,a)', '| ', &
          trim(case%viscous_scheme)//' | ', numbers(k), ' | ', substeps, ' | ', result%drag_coefficient, ' | ', &
          100 * (result%drag_coefficient / zick_homsy - 1), '% | ', &
          100 * (result%drag_coefficient / explicit%drag_coefficient - 1), '% | ', result%momentum, ' | ', &
          merge('yes', 'no ', result%steady), ' | ', result%steps, ' | ', result%wall_seconds, ' |'
    end do
  end do
  ! Stability beyond the steady state: 1500 steps at nu dt/dx^2 = 10 without the steady stop.
  case = settling_case_t(viscous_number=10.0_wp, max_steps=1500, steady_tolerance=0.0_wp, viscous_scheme='crank_nicolson')
  call run_settling_sphere(case, result)
  if (is_root()) print '(a,i0,a,f7.4,a,f7.3,a,es9.2,a,f7.1,a)', '1500 steps at nu dt/dx^2 = 10 (no steady stop): steps ', &
      result%steps, ', K ', result%drag_coefficient, ' (', 100 * (result%drag_coefficient / explicit%drag_coefficient - 1), &
      '% vs explicit), momentum ', result%momentum, ', wall ', result%wall_seconds, ' s'
  call parallel_stop()
end program bench_free_cn
