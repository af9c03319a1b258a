!> Two equal bodies pushed together by constant equal and opposite forces in fluid at rest, with the
!> sub-grid lubrication (make validate; docs/studies/validation.md, "Free approach under a constant
!> force"; validation/push_pair_case.f90). Prints, per run, the relative error of the time to reach
!> r, 0.1 r, 1e-2 r, 1e-3 r and 10 nm from 2 r, the largest relative errors of t(h) and h(t) over
!> 2 r .. 0.1 r, and of the time from 1e-2 r to 10 nm, against the quasi-steady approach
!> under the exact two-sphere resistance (spheres) or the time from 1e-2 r to 10 nm against the
!> curvature-scaled near-contact asymptote (needles tip to tip, disks face to face).
!> Arguments: 'stokes' (the 'stokes' rung: spheres at the hand-overs 1 r, the scene's default, and
!> 0.125 r, half a cell of D/dx = 8, then needles and disks), or 'resolved D width Re_p' (the
!> immersed boundary, squeeze_case's run_free_squeeze from rest 2 radii apart to 5 nm, the
!> hand-over of its incremental pressure, 0.5 cell; defaults 8 24 0.1).
program bench_push_pair
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use config_collision, only: default_lubrication_handover
  use squeeze_case, only: free_squeeze_case_t, free_squeeze_history_t, run_free_squeeze, squeeze_dynamic_viscosity
  use push_pair_case, only: push_case_t, push_history_t, run_stokes_push, quasi_steady_times, history_gap_error, &
                            history_time_error, history_time_at, tip_asymptote_time
  implicit none
  character(len=32) :: mode, argument
  type(push_case_t) :: case
  type(push_history_t) :: history
  type(free_squeeze_case_t) :: resolved
  type(free_squeeze_history_t) :: free

  call parallel_start()
  mode = 'stokes'
  if (command_argument_count() >= 1) call get_command_argument(1, mode)
  if (is_root()) write(*, '(a)') '| rung | pair | h_out | t(h)/t_ref(h) - 1 at h = r | 0.1 r | 1e-2 r | 1e-3 r | '// &
      '10 nm | max abs t(h)/t_ref - 1, 2 r .. 0.1 r | max abs h(t)/h_ref - 1, 2 r .. 0.1 r | '// &
      'time 1e-2 r -> 10 nm / ref - 1 |'
  if (is_root()) write(*, '(a)') '|---|---|---|---|---|---|---|---|---|---|---|'
  if (trim(mode) == 'stokes') then
    case%handover = 1.0_wp
    call run_stokes_push(case, history)
    call report_spheres('stokes', '1 r', history%time, history%gap, history%push, case%radius, case%viscosity)
    case%handover = 0.125_wp
    call run_stokes_push(case, history)
    call report_spheres('stokes', '0.125 r', history%time, history%gap, history%push, case%radius, case%viscosity)
    case%handover = 1.0_wp
    case%shape = 'needle'
    call run_stokes_push(case, history)
    call report_tips('needles')
    case%shape = 'disk'
    call run_stokes_push(case, history)
    call report_tips('disks')
  else
    resolved%diameter_cells = 8.0_wp
    resolved%width_cells = 24
    resolved%push_reynolds = 0.1_wp
    if (command_argument_count() >= 2) then
      call get_command_argument(2, argument)
      read(argument, *) resolved%diameter_cells
    end if
    if (command_argument_count() >= 3) then
      call get_command_argument(3, argument)
      read(argument, *) resolved%width_cells
    end if
    if (command_argument_count() >= 4) then
      call get_command_argument(4, argument)
      read(argument, *) resolved%push_reynolds
    end if
    resolved%start_gap_cells = resolved%diameter_cells          ! 2 radii
    resolved%lubrication = .true.
    resolved%handover_cells = default_lubrication_handover('resolved', 'resolved', resolved%pressure_scheme, 1.0_wp, 1.0_wp)
    resolved%max_steps = 400000
    ! 5 nm in cells of the case's box (1 mm long, 2 width cells)
    resolved%stop_gap_cells = 5.0e-9_wp / (1.0e-3_wp / (2 * resolved%width_cells))
    call run_free_squeeze(resolved, free)
    write(argument, '(a,f0.0)') 'resolved D/dx ', resolved%diameter_cells
    call report_spheres(trim(argument), '0.5 cell', free%time, free%gap, free%push, free%radius, squeeze_dynamic_viscosity)
    if (is_root()) write(*, '(a,i0,a,f0.1,a,l1)') '  steps ', free%steps, ', wall ', free%wall_seconds, ' s, reached ', &
                                                   free%reached
  end if
  call parallel_stop()

contains

  !> One row: t(h) / t_ref(h) - 1 at h = r, 0.1 r, 1e-2 r, 1e-3 r and 10 nm, the largest |t(h) /
  !> t_ref(h) - 1| and |h(t) / h_ref(t) - 1| over 2 r .. 0.1 r (20 gaps a decade), and the time from
  !> 1e-2 r to 10 nm over the reference's.
  subroutine report_spheres(rung, handover, time, gap, push, radius, viscosity)
    character(len=*), intent(in) :: rung, handover
    real(wp), intent(in) :: time(:), gap(:), push, radius, viscosity
    real(wp), allocatable :: gaps(:), times(:), marks(:), mark_times(:)
    character(len=:), allocatable :: row
    integer :: k
    gaps = [(radius * 10.0_wp**(log10(2.0_wp) - 0.05_wp * k), k = 1, 26)]   ! 2 r .. 0.1 r
    times = quasi_steady_times(push, radius, viscosity, 2.0_wp * radius, gaps)
    marks = [radius, 0.1_wp * radius, 1.0e-2_wp * radius, 1.0e-3_wp * radius, 1.0e-8_wp]
    mark_times = quasi_steady_times(push, radius, viscosity, 2.0_wp * radius, marks)
    row = '| '//rung//' | spheres | '//handover//' |'
    do k = 1, size(marks)
      row = row//' '//pct(history_time_at(time, gap, marks(k)) / mark_times(k) - 1.0_wp)//' |'
    end do
    row = row//' '//pct(history_time_error(time, gap, times, gaps))//' | '// &
          pct(history_gap_error(time, gap, times, gaps))//' | '// &
          pct((history_time_at(time, gap, marks(5)) - history_time_at(time, gap, marks(3))) &
              / (mark_times(5) - mark_times(3)) - 1.0_wp)//' |'
    if (is_root()) write(*, '(a)') row
  end subroutine report_spheres

  subroutine report_tips(pair)
    character(len=*), intent(in) :: pair
    if (is_root()) write(*, '(5a)') '| stokes | ', pair, ' | 1 r | - | - | - | - | - | - | - | '// &
        pct((history_time_at(history%time, history%gap, 1.0e-8_wp) &
             - history_time_at(history%time, history%gap, 1.0e-2_wp * case%radius)) &
            / tip_asymptote_time(history, case%viscosity, 1.0e-2_wp * case%radius, 1.0e-8_wp) - 1.0_wp), ' (asymptote) |'
  end subroutine report_tips

  function pct(x) result(text)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: text
    character(len=16) :: buffer
    write(buffer, '(sp,f0.1,a)') 100.0_wp * x, '%'
    text = trim(buffer)
  end function pct
end program bench_push_pair
