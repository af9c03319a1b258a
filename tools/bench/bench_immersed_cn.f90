!> The Crank-Nicolson predictor with the immersed-boundary rows (hypre) on the sphere array.
program bench_immersed_cn
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, is_root
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array
  implicit none
  real(wp), parameter :: zick_homsy_0125 = 4.292_wp
  type(sphere_array_case_t) :: case
  type(sphere_array_result_t) :: result
  real(wp) :: numbers(4) = [0.06_wp, 0.06_wp, 5.0_wp, 5.0_wp]
  integer :: n
  call parallel_start()
  case%cells = 13
  do n = 1, size(numbers)
    case%viscous_scheme = merge('explicit      ', 'crank_nicolson', n == 1)
    if (n == 4) case%steady_tolerance = 1e-13_wp
    case%viscous_number = numbers(n)
    call run_sphere_array(case, result)
    if (is_root()) print '(a,f6.2,a,f8.4,a,f8.3,a,i0,a,f6.2,a,i0,a,f8.2)', 'r ', numbers(n), ' K ', result%drag_coefficient, &
        ' err% ', 100 * (result%drag_coefficient / zick_homsy_0125 - 1), ' steps ', result%steps, ' mean it ', &
        result%mean_sweeps, ' max ', result%max_sweeps, ' s ', result%wall_seconds
  end do
end program bench_immersed_cn
