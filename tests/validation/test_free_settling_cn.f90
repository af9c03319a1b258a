! checks: 12
!> Crank-Nicolson + hypre with a free particle (docs/studies/validation.md, "Crank-Nicolson with free
!> particles"): the settling sphere of test_free_settling (module settling_sphere_case, 13^3,
!> D/dx 8.06, phi = 0.125, calcite density ratio 2.72) with &fluid viscous_scheme =
!> 'crank_nicolson' at nu dt/dx^2 = 1, 5 and 10 (12, 60 and 120 times the explicit-diffusion bound
!> 1/12 the deck checks apply, 1/(4 nu sum 1/dx_i^2)). Each run must reach the terminal
!> velocity (stable: the slip vector changes by less than 1e-7 of itself per step; the predictor's
!> hypre tolerance, 1e-8, leaves step-to-step noise of that order in it), its drag coefficient
!> K = W / (6 pi mu a U_s) must agree with the fixed array of the same cell with explicit diffusion
!> (K = 4.2794, docs/studies/validation.md "Immersed boundary") and with Zick & Homsy (1982, J. Fluid Mech.
!> 115, 13, Table 2: K = 4.292 at phi = 0.125), and the box's momentum (no net force on it) must
!> stay small against rho_f L^3 U_s. Measured (tools/bench/bench_free_cn.f90): K = 4.2699, 4.2578,
!> 4.2438 (-0.22%, -0.50%, -0.83% against the explicit free sphere's 4.2793), momentum 2.5e-6, 3.8e-4,
!> 1.5e-4, steady in 102, 221, 286 steps. Without the history and drag terms of the lagged-reaction
!> estimate (module resolved_hydrodynamics) the run at 10 diverged within 50 steps.
program test_free_settling_cn
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start
  use settling_sphere_case, only: settling_case_t, settling_result_t, run_settling_sphere
  use test_framework, only: test_start, test_finish, check, check_close, check_below
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp   ! Zick & Homsy 1982, Table 2, phi = 0.125
  real(wp), parameter :: fixed_array_13 = 4.2794_wp   ! the fixed sphere at 13^3, explicit (docs/studies/validation.md)
  real(wp), parameter :: numbers(3) = [1.0_wp, 5.0_wp, 10.0_wp]       ! nu dt / dx^2
  real(wp), parameter :: to_explicit(3) = [0.005_wp, 0.01_wp, 0.015_wp]   ! bounds on K against the fixed array
  real(wp), parameter :: to_reference(3) = [0.01_wp, 0.015_wp, 0.02_wp]   ! and against Zick & Homsy
  real(wp), parameter :: momentum_bound(3) = [1.0e-5_wp, 1.0e-3_wp, 1.0e-3_wp]
  type(settling_case_t) :: case
  type(settling_result_t) :: result
  character(len=160) :: text
  character(len=8) :: tag
  integer :: k

  call parallel_start()
  call test_start('free_settling_cn')
  do k = 1, size(numbers)
    write(tag, '(i0)') nint(numbers(k))
    case = settling_case_t(viscous_number=numbers(k), viscous_scheme='crank_nicolson', max_steps=800, &
                           steady_tolerance=1.0e-7_wp)
    call run_settling_sphere(case, result)
    write(text, '(a,f5.1,a,f7.4,a,f6.2,a,f6.2,a,es9.2,a,i0)') 'CN settling sphere nu dt/dx^2 ', numbers(k), ': K ', &
        result%drag_coefficient, ', vs fixed array ', 100 * (result%drag_coefficient / fixed_array_13 - 1), &
        '%, vs Z&H ', 100 * (result%drag_coefficient / zick_homsy_0125 - 1), '%, momentum ', result%momentum, &
        ', steps ', result%steps
    print '(a)', trim(text)
    call check(result%steady, 'cn_settling_'//trim(tag)//'_stable_reaches_terminal_velocity')
    call check_close(result%drag_coefficient, fixed_array_13, to_explicit(k), 'cn_settling_'//trim(tag)//'_drag_vs_explicit')
    call check_close(result%drag_coefficient, zick_homsy_0125, to_reference(k), 'cn_settling_'//trim(tag)//'_drag_zick_homsy')
    call check_below(abs(result%momentum), momentum_bound(k), 'cn_settling_'//trim(tag)//'_box_momentum_small')
  end do
  call test_finish()
end program test_free_settling_cn
