!> The box's momentum budget of a settling body (docs/studies/validation.md, "Needle and disk settling at a
!> tilt"; module settling_sphere_case): the momentum rho_f dV sum_{fluid u nodes} u + m U_p, which no
!> net force changes, against what the u nodes that changed status (covered or uncovered by the
!> moving surface) carried across the budget's boundary, both over rho_f L^3 U_s, with the number of
!> status changes. One row per shape; the body moves about W / (6 pi mu r) dt per step, so a large
!> weight (U_s up to 1e-4 m/s, Re below 0.1) sweeps its surface across nodes within a short run.
!> Arguments: box cells, steady tolerance per step (0: run all steps), net weight (N), steps, then
!> shapes (sphere, needle, disk; needle and disk of aspect 5, thin dimension 4.4 cells, at 45
!> degrees from gravity). Default: 32 2e-6 2.5e-12 40000 sphere needle disk.
program bench_settling_momentum
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use settling_sphere_case, only: settling_case_t, settling_result_t, run_settling_sphere
  implicit none
  type(settling_case_t) :: case
  type(settling_result_t) :: result
  character(len=32) :: argument
  character(len=8), allocatable :: shapes(:)
  integer :: s, count

  call parallel_start()
  case = settling_case_t(cells=32, steady_tolerance=2.0e-6_wp, max_steps=40000, thin_cells=4.4_wp, tilt_degrees=45.0_wp)
  count = command_argument_count()
  if (count >= 1) call read_argument(1, case%cells)
  if (count >= 2) call read_real_argument(2, case%steady_tolerance)
  if (count >= 3) call read_real_argument(3, case%weight)
  if (count >= 4) call read_argument(4, case%max_steps)
  shapes = [character(len=8) :: 'sphere', 'needle', 'disk']
  if (count >= 5) then
    deallocate(shapes)
    allocate(shapes(count - 4))
    do s = 5, count
      call get_command_argument(s, shapes(s - 4))
    end do
  end if
  if (is_root()) then
    print '(a)', '| shape | box | W (N) | steps | U_s (m/s) | momentum | carried by status changes | momentum - carried | ' // &
        'status changes |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|'
  end if
  do s = 1, size(shapes)
    case%shape = shapes(s)
    if (shapes(s) == 'sphere') case%volume_fraction = 0.125_wp
    call run_settling_sphere(case, result)
    if (is_root()) print '(a,a,a,i0,a,es8.1,a,i0,a,es9.2,a,es10.3,a,es10.3,a,es9.2,a,i0,a)', '| ', trim(shapes(s)), ' | ', &
        case%cells, '^3 | ', case%weight, ' | ', result%steps, ' | ', norm2(result%slip_vector), ' | ', result%momentum, &
        ' | ', result%status_momentum, ' | ', result%momentum - result%status_momentum, ' | ', result%status_changes, ' |'
  end do
  call parallel_stop()

contains

  subroutine read_argument(position, value)
    integer, intent(in) :: position
    integer, intent(inout) :: value
    call get_command_argument(position, argument)
    read(argument, *) value
  end subroutine read_argument

  subroutine read_real_argument(position, value)
    integer, intent(in) :: position
    real(wp), intent(inout) :: value
    call get_command_argument(position, argument)
    read(argument, *) value
  end subroutine read_real_argument
end program bench_settling_momentum
