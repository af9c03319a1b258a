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
!> hand-over of its incremental pressure, 0.5 cell; defaults 8 24 0.1), or
!> 'resolved-tips shape thin n_x n_yz Re_p [start [aspect]]' (the same for a needle pair tip to tip
!> or a disk pair face to face, shape 'needle' or 'disk': the thin dimension (needle minor axis,
!> disk thickness) thin cells, box n_x x n_yz x n_yz cells (1 mm along x), U_p r / nu = Re_p (r the
!> volume-equivalent radius), from rest start cells apart (default 2) to 5 nm, aspect ratio aspect
!> (default push_case_t's, 5); the decks' pressure-free projection and its hand-over, 0.75 cell).
!> It prints the times from 1e-2 r and 1e-3 r to 10 nm and from 0.1 r to 1e-2 r over the
!> curvature-scaled asymptote's, the asymptote's drag term over the whole in each range, and the
!> split of the resistance at 0.1 r, 1e-2 r, 1e-3 r and 10 nm (resolved force over zeta U, model
!> force over its leading term).
program bench_push_pair
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use error_handling, only: fatal
  use config_collision, only: default_lubrication_handover
  use squeeze_case, only: free_squeeze_case_t, free_squeeze_history_t, run_free_squeeze, squeeze_dynamic_viscosity, &
                          free_squeeze_sample, pushed_tips_case
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
  if (trim(mode) == 'resolved-tips') then
    call resolved_tips()
    call parallel_stop()
    stop, quiet=.true.   ! no note on the underflow flags the DLVO exponentials raise (harmless)
  end if
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

  !> The resolved rung of a needle or disk pair (program header): one table row.
  subroutine resolved_tips()
    type(push_history_t) :: tips
    character(len=8) :: shape
    real(wp) :: gap, speed, start_gap, aspect_ratio, push_reynolds
    real(wp) :: thin_cells, marks(4), measured(4), reference(3), drag_share(3)
    integer :: cells(2), k
    character(len=160) :: row
    character(len=16) :: steps_text
    if (command_argument_count() < 6) call fatal('bench_push_pair resolved-tips: give shape thin n_x n_yz Re_p '// &
                                                 '[start [aspect]], e.g. resolved-tips needle 6 96 24 0.003')
    call get_command_argument(2, shape)
    call get_command_argument(3, argument)
    read(argument, *) thin_cells
    call get_command_argument(4, argument)
    read(argument, *) cells(1)
    call get_command_argument(5, argument)
    read(argument, *) cells(2)
    call get_command_argument(6, argument)
    read(argument, *) push_reynolds
    start_gap = 2.0_wp
    if (command_argument_count() >= 7) then
      call get_command_argument(7, argument)
      read(argument, *) start_gap
    end if
    aspect_ratio = case%aspect_ratio
    if (command_argument_count() >= 8) then
      call get_command_argument(8, argument)
      read(argument, *) aspect_ratio
    end if
    if (shape /= 'needle' .and. shape /= 'disk') call fatal('bench_push_pair resolved-tips: shape '''//trim(shape)// &
                                                            '''; allowed: needle, disk')
    if (.not. (thin_cells >= 4.0_wp)) call fatal('bench_push_pair resolved-tips: the thin dimension must be >= 4 cells')
    resolved = pushed_tips_case(shape, aspect_ratio, thin_cells, [cells(1), cells(2), cells(2)], push_reynolds, &
                                start_gap, 5.0e-9_wp)
    call run_free_squeeze(resolved, free)
    tips%push = free%push
    tips%axial_drag = free%axial_drag
    tips%reduced_radius = free%reduced_radius
    ! The ranges 1e-2 r -> 10 nm, 1e-3 r -> 10 nm and 0.1 r -> 1e-2 r.
    marks = [0.1_wp * free%radius, 1.0e-2_wp * free%radius, 1.0e-3_wp * free%radius, 1.0e-8_wp]
    measured = [(history_time_at(free%time, free%gap, marks(k)), k = 1, 4)]
    reference = [tip_asymptote_time(tips, squeeze_dynamic_viscosity, marks(2), marks(4)), &
                 tip_asymptote_time(tips, squeeze_dynamic_viscosity, marks(3), marks(4)), &
                 tip_asymptote_time(tips, squeeze_dynamic_viscosity, marks(1), marks(2))]
    drag_share = tips%axial_drag * [marks(2) - marks(4), marks(3) - marks(4), marks(1) - marks(2)] &
                 / (2.0_wp * tips%push * reference)
    if (.not. is_root()) return
    write(steps_text, '(i0)') free%steps
    write(*, '(a)') '| pair | aspect ratio | thin cells | box cells | 2 r / dx | start gap | U_p r/nu | '// &
        'time 1e-2 r -> 10 nm / asymptote - 1 | 1e-3 r -> 10 nm | 0.1 r -> 1e-2 r | drag term / asymptote, '// &
        'the three ranges | R_eff / r | steps | wall |'
    write(*, '(a)') '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|'
    write(row, '(a,f0.1,a,f0.1,a,3(i0,a))') '| '//trim(shape)//'s | ', resolved%aspect_ratio, ' | ', thin_cells, &
        ' | ', cells(1), ' x ', cells(2), ' x ', cells(2), ' | '
    write(*, '(a)') trim(row)//' '//fixed(resolved%diameter_cells, '(f6.2)')//' | '// &
        fixed(resolved%start_gap_cells, '(f6.2)')//' cells ('// &
        fixed(resolved%start_gap_cells * 2.0_wp / resolved%diameter_cells, '(f6.3)')//' r) | '// &
        fixed(resolved%push_reynolds, '(f8.4)')//' | '//pct((measured(4) - measured(2)) / reference(1) - 1.0_wp)//' | '// &
        pct((measured(4) - measured(3)) / reference(2) - 1.0_wp)//' | '// &
        pct((measured(2) - measured(1)) / reference(3) - 1.0_wp)//' | '//fixed(drag_share(1), '(f6.3)')//' / '// &
        fixed(drag_share(2), '(f6.3)')//' / '//fixed(drag_share(3), '(f6.3)')//' | '// &
        fixed(tips%reduced_radius / free%radius, '(f7.4)')//' | '// &
        trim(steps_text)//' | '//fixed(free%wall_seconds, '(f0.1)')//' s |'
    write(*, '(a,l1,a,i0,a)') '  reached ', free%reached, ', most ghost-row sweeps ', free%max_sweeps_seen, &
        ', zeta / (6 pi mu r) '//fixed(free%axial_drag / (6.0_wp * pi * squeeze_dynamic_viscosity * free%radius), &
        '(f7.4)')//', r '//fixed(free%radius, '(es10.3)')//' m, at the end lateral offset '// &
        fixed(free%lateral_offset / free%cell, '(es9.2)')//' cells, tilt '//fixed(free%tilt, '(es9.2)')//' rad'
    ! The split of the resistance at 0.1 r, 1e-2 r, 1e-3 r and 10 nm: the resolved force over zeta U,
    ! the model's over the leading term of its R_sub(h) 2 U (6 pi mu R_eff^2 (1/h - 1/h_out), the
    ! relative speed 2 U).
    do k = 1, 4
      gap = marks(k)
      speed = free_squeeze_sample(free, free%speed, gap)
      row = 'above h_out'
      if (gap < resolved%handover_cells * free%cell) row = fixed(free_squeeze_sample(free, free%lubrication, gap) &
          / (6.0_wp * pi * squeeze_dynamic_viscosity * tips%reduced_radius**2 &
             * (1.0_wp / gap - 1.0_wp / (resolved%handover_cells * free%cell)) * 2.0_wp * speed), '(f8.4)')
      write(*, '(a)') '  h / r '//fixed(gap / free%radius, '(es9.2)')//': U / (F / zeta) '// &
          fixed(speed * free%axial_drag / free%push, '(f8.4)')//', resolved / (zeta U) '// &
          fixed(free_squeeze_sample(free, free%resolved, gap) / (free%axial_drag * speed), '(f8.4)')// &
          ', model / (6 pi mu R_eff^2 (1/h - 1/h_out) 2 U) '//trim(row)
    end do
  end subroutine resolved_tips

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

  !> x written with the edit descriptor format, without blanks.
  function fixed(x, format) result(text)
    real(wp), intent(in) :: x
    character(len=*), intent(in) :: format
    character(len=:), allocatable :: text
    character(len=32) :: buffer
    write(buffer, format) x
    text = trim(adjustl(buffer))
  end function fixed

  function pct(x) result(text)
    real(wp), intent(in) :: x
    character(len=:), allocatable :: text
    character(len=16) :: buffer
    write(buffer, '(sp,f12.1,a)') 100.0_wp * x, '%'   ! a fixed width prints the leading zero (-0.2%, not -.2%)
    text = trim(adjustl(buffer))
  end function pct
end program bench_push_pair
