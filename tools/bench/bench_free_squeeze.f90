!> Free pair approaching head-on (make validate; docs/studies/validation.md, "Lubrication", "Free pair
!> approach"): two spheres resolved by the immersed boundary
!> (&scene particle_coupling = 'resolved') pushed together from rest by constant opposite forces in
!> fluid at rest (validation/squeeze_case.f90, run_free_squeeze), without and with the sub-grid
!> lubrication of the particle system at the given hand-over gaps. Per run, a Markdown table at the
!> gaps 4 ... 0.1 cells: the approach speed U of each sphere against the reference approach
!> (approach_reference: Brenner's resistance, one-dimensional), the time to close from 4 cells
!> against the reference's, and the forces along the line of centres over Brenner's at the measured
!> speed, F_B = 6 pi mu a beta(h) U: the resolved one, the lubrication one and their sum.
!> Arguments (all optional): D/dx, box width n_y (cells), U_p a / nu, then the hand-over gaps in
!> cells, 0 meaning lubrication off (default 8 32 0.1 0 1 0.5). A leading option
!> pressure=incremental|non_incremental sets &fluid pressure_scheme (default 'incremental').
program bench_free_squeeze
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use error_handling, only: fatal
  use squeeze_case, only: free_squeeze_case_t, free_squeeze_history_t, run_free_squeeze, approach_reference, &
                          free_squeeze_sample, &
                          brenner_squeeze_coefficient, squeeze_dynamic_viscosity
  implicit none
  real(wp), parameter :: table_gaps(*) = [4.0_wp, 3.0_wp, 2.0_wp, 1.5_wp, 1.0_wp, 0.75_wp, 0.5_wp, 0.25_wp, 0.1_wp]
  type(free_squeeze_case_t) :: case
  type(free_squeeze_history_t) :: history
  real(wp), allocatable :: handovers(:)
  real(wp) :: reference_speed(size(table_gaps)), reference_time(size(table_gaps)), gaps(size(table_gaps))
  real(wp) :: speed, time, resolved, lubricated, brenner, time_start, reference_start
  character(len=32) :: argument, setting
  integer :: count, r, g
  integer :: shift   ! leading options before the positional arguments

  call parallel_start()
  count = command_argument_count()
  shift = 0
  if (count >= 1) then
    call get_command_argument(1, argument)
    if (index(argument, 'pressure=') == 1) then
      case%pressure_scheme = argument(len('pressure=') + 1:)
      if (case%pressure_scheme /= 'incremental' .and. case%pressure_scheme /= 'non_incremental') &
        call fatal('bench_free_squeeze: pressure = '//trim(case%pressure_scheme)//'; allowed: incremental, non_incremental')
      shift = 1
      count = count - 1
    end if
  end if
  if (count >= 1) call read_argument(1, case%diameter_cells)
  if (count >= 2) then
    call get_command_argument(2 + shift, argument)
    read(argument, *) case%width_cells
  end if
  if (count >= 3) call read_argument(3, case%push_reynolds)
  if (count >= 4) then
    allocate(handovers(count - 3))
    do r = 4, count
      call read_argument(r, handovers(r - 3))
    end do
  else
    handovers = [0.0_wp, 1.0_wp, 0.5_wp]
  end if
  case%stop_gap_cells = 0.9_wp * minval(table_gaps)

  do r = 1, size(handovers)
    case%lubrication = handovers(r) > 0
    if (case%lubrication) case%handover_cells = handovers(r)
    call run_free_squeeze(case, history)
    gaps = table_gaps * history%cell
    call approach_reference(history%push, history%radius, history%mass + history%added_mass, &
                            case%start_gap_cells * history%cell, gaps, &
                            reference_speed, reference_time)
    if (.not. is_root()) cycle
    setting = 'off'
    if (case%lubrication) setting = 'on, h_out = '//trim(number(handovers(r)))//' cells'
    print '(a,f4.1,a,i0,a,i0,a,f5.3,a,a,a,a,a,i0,a,i0,a,f7.1,a)', '**D/dx = ', case%diameter_cells, ', box ', &
        2 * case%width_cells, 'x', case%width_cells, '², U_p a/nu = ', case%push_reynolds, ', lubrication ', &
        trim(setting), ', pressure ', trim(case%pressure_scheme), '** (', history%steps, ' fluid steps, at most ', &
        history%max_sweeps_seen, &
        ' sweeps, ', history%wall_seconds, ' s)'
    print '(a)', ''
    print '(a)', '| h/dx | h/a | U (m/s) | U / U_ref - 1 | closing time from 4 cells / ref - 1 | ' // &
        'F_resolved / F_B | F_lubrication / F_B | (F_resolved + F_lubrication) / F_B - 1 |'
    print '(a)', '|---|---|---|---|---|---|---|---|'
    do g = 1, size(table_gaps)
      if (minval(history%gap) > gaps(g)) exit
      speed = free_squeeze_sample(history, history%speed, gaps(g))
      time = free_squeeze_sample(history, history%time, gaps(g))
      resolved = free_squeeze_sample(history, history%resolved, gaps(g))
      lubricated = free_squeeze_sample(history, history%lubrication, gaps(g))
      brenner = 6.0_wp * pi * squeeze_dynamic_viscosity * history%radius &
                * brenner_squeeze_coefficient(gaps(g) / history%radius) * speed
      if (g == 1) then
        time_start = time
        reference_start = reference_time(1)
      end if
      print '(a,f5.2,a,f7.4,a,es10.3,a,f7.2,a,a,a,f6.3,a,f6.3,a,f7.2,a)', '| ', table_gaps(g), ' | ', &
          gaps(g) / history%radius, ' | ', speed, ' | ', 100 * (speed / reference_speed(g) - 1), '% | ', &
          trim(closing_error()), ' | ', resolved / brenner, ' | ', lubricated / brenner, ' | ', &
          100 * ((resolved + lubricated) / brenner - 1), '% |'
    end do
    print '(a)', ''
  end do
  call parallel_stop()

contains

  subroutine read_argument(position, value)
    integer, intent(in) :: position
    real(wp), intent(out) :: value
    call get_command_argument(position + shift, argument)
    read(argument, *) value
  end subroutine read_argument

  function number(value) result(text)
    real(wp), intent(in) :: value
    character(len=16) :: text
    write(text, '(g0.3)') value
  end function number

  function closing_error() result(text)
    character(len=16) :: text
    if (g == 1) then
      text = '(start)'
    else
      write(text, '(f7.2,a)') 100 * ((time - time_start) / (reference_time(g) - reference_start) - 1), '%'
    end if
  end function closing_error
end program bench_free_squeeze
