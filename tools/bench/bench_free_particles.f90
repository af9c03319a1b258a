!> Free particles resolved by the immersed boundary (make validate; docs/validation.md, "Free
!> particles"): a sphere settling in the periodic cube (module settling_sphere_case) at D/dx about
!> 8, 12 and 16 (phi = 0.125), its drag coefficient K = W / (6 pi mu a U_s) against Zick & Homsy
!> (1982, J. Fluid Mech. 115, 13, Table 2: K = 4.292) and against the fixed sphere of the same cell
!> (docs/validation.md, "Immersed boundary": 4.2794, 4.2884, 4.2802); then at D/dx 8 the density
!> ratios 2.72, 1.1, 0.5 and 0.3 (a buoyant sphere rises; at 1 there is no net weight) with and
!> without the added-mass stabilisation. Prints Markdown tables.
program bench_free_particles
  use agglo_kinds, only: wp
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use settling_sphere_case, only: settling_case_t, settling_result_t, run_settling_sphere
  implicit none
  real(wp), parameter :: zick_homsy = 4.292_wp
  integer, parameter :: cells(3) = [13, 19, 26]
  real(wp), parameter :: fixed(3) = [4.2794_wp, 4.2884_wp, 4.2802_wp]
  real(wp), parameter :: ratios(4) = [2.72_wp, 1.1_wp, 0.5_wp, 0.3_wp]
  type(settling_case_t) :: case
  type(settling_result_t) :: result
  integer :: d, r, s
  logical :: stabilise

  call parallel_start()
  if (is_root()) then
    print '(a)', '| cells | D/dx | rho_p/rho_f | stabilised | K | vs Z&H | vs fixed sphere | momentum | steps | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|---|'
  end if
  do d = 1, size(cells)
    case = settling_case_t(cells=cells(d), max_steps=40000)
    call run_settling_sphere(case, result)
    call print_row(case, result, fixed(d))
  end do
  do r = 1, size(ratios)
    do s = 1, 2   ! with, then without the stabilisation
      stabilise = s == 1
      case = settling_case_t(cells=13, density_ratio=ratios(r), stabilise=stabilise, max_steps=4000)
      call run_settling_sphere(case, result)
      call print_row(case, result, fixed(1))
    end do
  end do
  call parallel_stop()

contains

  subroutine print_row(case, result, fixed_k)
    type(settling_case_t), intent(in) :: case
    type(settling_result_t), intent(in) :: result
    real(wp), intent(in) :: fixed_k
    character(len=24) :: k_text, zh_text, fixed_text
    if (.not. is_root()) return
    if (result%steady .and. ieee_is_finite(result%drag_coefficient)) then
      write(k_text, '(f7.4)') result%drag_coefficient
      write(zh_text, '(f6.2,a)') 100 * (result%drag_coefficient / zick_homsy - 1), '%'
      write(fixed_text, '(f6.2,a)') 100 * (result%drag_coefficient / fixed_k - 1), '%'
    else
      k_text = 'not steady'
      zh_text = '-'
      fixed_text = '-'
    end if
    print '(a,i0,a,f5.2,a,f4.2,a,a,a,a,a,a,a,a,a,es9.2,a,i0,a,f7.1,a)', '| ', case%cells, '^3 | ', &
        result%diameter_cells, ' | ', case%density_ratio, ' | ', merge('yes', 'no ', case%stabilise), ' | ', &
        trim(k_text), ' | ', trim(zh_text), ' | ', trim(fixed_text), ' | ', result%momentum, ' | ', result%steps, &
        ' | ', result%wall_seconds, ' |'
  end subroutine print_row
end program bench_free_particles
