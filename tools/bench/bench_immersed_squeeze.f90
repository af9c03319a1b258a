!> Squeeze film (make validate; docs/studies/validation.md, "Lubrication"; ladder rung 11):
!> two equal spheres approaching head-on at fixed speed in Stokes flow, the gap held fixed and the
!> flow run to steady state at each gap (validation/squeeze_case.f90), against Brenner's exact force
!> of two spheres. The gap (in cells) below which the error passes 10-20% is where the immersed
!> boundary stops carrying the squeeze force: the hand-over gap of the sub-grid lubrication
!> (&collision lubrication_handover). Prints a Markdown table. Besides the force itself, the table
!> gives the error of its increase from the first (widest) gap of the list, F(h) - F(h_1) against
!> the same difference of Brenner's force: the periodic box changes the force by an amount that
!> hardly depends on h, and the increase is what the sub-grid model must add below the hand-over
!> (R(h) - R(h_out), src/particles/lubrication.f90). The last four error columns are those of the
!> total force with the sub-grid model on, F(h) + (R(h) - R(h_out)) 2U, for h_out = 0.5, 0.75, 1 and 2
!> cells.
!> Optional arguments: D/dx, box width n_y (cells), then the gaps in cells, the widest first (default
!> 8, 32, and 8 6 4 3 2 1.5 1 0.75 0.5 0.25 0.1 0.02 0.004). Leading options, before the rest, for
!> this ladder and the spheroids': pressure=incremental|non_incremental (&fluid pressure_scheme;
!> default 'incremental'), viscous=nu dt/dx^2 (default 0.06) and, for the spheroids, box=NX,NY,NZ
!> (cells; default spheroid_squeeze_box).
program bench_immersed_squeeze
  use agglo_kinds, only: wp
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use error_handling, only: fatal
  use squeeze_case, only: squeeze_case_t, squeeze_result_t, run_squeeze, squeeze_speed, squeeze_dynamic_viscosity
  use lubrication, only: lubrication_model_t, lubrication_geometry_t, lubrication_subgrid_resistance
  use spheroid_squeeze_case, only: spheroid_squeeze_case_t, spheroid_squeeze_result_t, run_spheroid_squeeze, &
                                   spheroid_squeeze_configurations
  implicit none
  type(squeeze_case_t) :: case
  type(squeeze_result_t) :: result, widest
  real(wp), allocatable :: gaps(:)
  character(len=32) :: argument
  character(len=32), allocatable :: arguments(:)
  integer :: box_cells(3) = 0   ! the spheroids' box (cells); 0: spheroid_squeeze_box
  integer :: g, count
  character(len=*), parameter :: row_format = &
      '(a,f4.1,a,i0,a,i0,a,f6.3,a,f7.4,a,es11.4,a,es11.4,a,f7.2,a,f7.2,a,f7.2,a,f7.2,a,f7.2,a,f7.2,a,i0,a,a,a,f7.1,a)'

  call parallel_start()
  call read_options()
  if (is_root()) print '(a,a,a,f6.4)', 'pressure_scheme = ', trim(case%pressure_scheme), ', nu dt/dx^2 = ', &
                                      case%viscous_number
  count = size(arguments)
  if (count >= 1 .and. arguments(1) == 'spheroids') then
    call spheroid_ladder()
    call parallel_stop()
    stop
  end if
  if (count >= 1) read(arguments(1), *) case%diameter_cells
  if (count >= 2) read(arguments(2), *) case%width_cells
  if (count >= 3) then
    allocate(gaps(count - 2))
    do g = 3, count
      read(arguments(g), *) gaps(g - 2)
    end do
  else
    gaps = [8.0_wp, 6.0_wp, 4.0_wp, 3.0_wp, 2.0_wp, 1.5_wp, 1.0_wp, 0.75_wp, 0.5_wp, 0.25_wp, 0.1_wp, 0.02_wp, &
            0.004_wp]
  end if
  if (is_root()) then
    print '(a)', '| D/dx | box (cells) | h/dx | h/a | F resolved (N) | F Brenner (N) | error | ' // &
        'error of F(h) - F(widest) | total error, h_out = 0.5 cell | h_out = 0.75 cell | h_out = 1 cell | ' // &
        'h_out = 2 cells | steps | steady | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|'
  end if
  do g = 1, size(gaps)
    case%gap_cells = gaps(g)
    call run_squeeze(case, result)
    if (g == 1) widest = result
    if (is_root()) print row_format, '| ', case%diameter_cells, ' | ', 2 * case%width_cells, 'x', case%width_cells, &
        '^2 | ', case%gap_cells, ' | ', result%gap_over_radius, ' | ', result%force, ' | ', result%reference, ' | ', &
        100 * result%error, '% | ', 100 * increase_error(), '% | ', 100 * total_error(0.5_wp), '% | ', &
        100 * total_error(0.75_wp), '% | ', 100 * total_error(1.0_wp), '% | ', &
        100 * total_error(2.0_wp), '% | ', result%steps, ' | ', &
        trim(merge('yes', 'no ', result%steady)), ' | ', result%wall_seconds, ' |'
  end do
  call parallel_stop()

contains

  !> The command line without its leading options (module header) into arguments(:); the options set
  !> case%pressure_scheme, case%viscous_number (the spheroid ladder copies both) and box_cells.
  subroutine read_options()
    integer :: position, total, first, status
    character(len=32) :: value
    total = command_argument_count()
    first = 1
    do position = 1, total
      call get_command_argument(position, argument)
      if (index(argument, '=') == 0) exit
      value = argument(index(argument, '=') + 1:)
      select case (argument(:index(argument, '=') - 1))
      case ('pressure')
        if (value /= 'incremental' .and. value /= 'non_incremental') &
          call fatal('bench_immersed_squeeze: pressure = '//trim(value)//'; allowed: incremental, non_incremental')
        case%pressure_scheme = value
      case ('box')
        read(value, *, iostat=status) box_cells
        if (status /= 0 .or. any(box_cells < 4)) &
          call fatal('bench_immersed_squeeze: box = '//trim(value)//'; allowed: NX,NY,NZ cells, each >= 4')
      case ('viscous')
        read(value, *, iostat=status) case%viscous_number
        if (status /= 0 .or. .not. (case%viscous_number > 0 .and. case%viscous_number < 1.0_wp / 12)) &
          call fatal('bench_immersed_squeeze: viscous = '//trim(value)//'; allowed: 0 < nu dt/dx^2 < 1/12')
      case default
        call fatal('bench_immersed_squeeze: option '//trim(argument)//'; allowed: pressure=, viscous=, box=')
      end select
      first = position + 1
    end do
    allocate(arguments(total - first + 1))
    do position = first, total
      call get_command_argument(position, arguments(position - first + 1))
    end do
  end subroutine read_options

  !> (F(h) - F(h_1)) / (F_B(h) - F_B(h_1)) - 1; 0 at the widest gap itself.
  real(wp) function increase_error()
    increase_error = 0
    if (g > 1) increase_error = (result%force - widest%force) / (result%reference - widest%reference) - 1
  end function increase_error

  !> (F(h) + R_sub(h) 2U) / F_B(h) - 1 with the sub-grid model handing over at handover cells (equal
  !> spheres: R_eff = a/2; the roughness far below the table's gaps).
  real(wp) function total_error(handover)
    real(wp), intent(in) :: handover
    type(lubrication_model_t) :: model
    type(lubrication_geometry_t) :: geometry
    model = lubrication_model_t(dynamic_viscosity=squeeze_dynamic_viscosity, outer_gap=handover * result%cell, &
                                roughness=1.0e-12_wp * result%cell)
    geometry = lubrication_geometry_t(reduced_radius=0.5_wp * result%radius, radius1=result%radius, radius2=result%radius)
    total_error = (result%force + lubrication_subgrid_resistance(model, geometry, case%gap_cells * result%cell) &
                   * 2.0_wp * squeeze_speed) / result%reference - 1
  end function total_error

  ! ---- Needles and disks (validation/spheroid_squeeze_case.f90) ----------------------------------
  !> `bench_immersed_squeeze spheroids [r/dx [configuration|all [gaps...]]]`: two needles or disks of
  !> aspect 5 (volume-equivalent radius r/dx, default 6, about the paper's resolution) in the five
  !> configurations of the case (default all) at fixed gaps (cells, the widest first; default 4 2 1
  !> 0.5), against the sub-grid model's resistance R(h) 2U at the closest points (module lubrication).
  !> "Rise" compares F(h) - F(h_1) with R(h) - R(h_1) (h_1 the widest gap), "leading" the same with
  !> the Reynolds film 6 pi mu R_eff^2 2U / h alone. Prints a Markdown table.
  subroutine spheroid_ladder()
    type(spheroid_squeeze_case_t) :: spheroid_case
    type(spheroid_squeeze_result_t) :: row, first
    character(len=8), allocatable :: configurations(:)
    real(wp), allocatable :: spheroid_gaps(:)
    integer :: c, k
    character(len=*), parameter :: spheroid_format = '(a,a,a,i0,a,i0,a,i0,a,f5.2,a,f6.3,a,f7.2,a,f7.2,a,' // &
        'es11.4,a,es11.4,a,f7.3,a,a,a,a,a,i0,a,a,a,f7.1,a)'

    if (count >= 2) read(arguments(2), *) spheroid_case%radius_cells
    configurations = spheroid_squeeze_configurations
    if (count >= 3) then
      if (arguments(3) /= 'all') configurations = [character(len=8) :: arguments(3)]
    end if
    if (count >= 4) then
      allocate(spheroid_gaps(count - 3))
      do k = 4, count
        read(arguments(k), *) spheroid_gaps(k - 3)
      end do
    else
      spheroid_gaps = [4.0_wp, 2.0_wp, 1.0_wp, 0.5_wp]
    end if
    spheroid_case%run%steady_tolerance = 3.0e-7_wp
    spheroid_case%run%max_steps = 40000
    spheroid_case%run%pressure_scheme = case%pressure_scheme
    spheroid_case%run%viscous_number = case%viscous_number
    if (is_root()) then
      print '(a)', '| configuration | box (cells) | r/dx | h/dx | R_eff/dx | a_1/dx | F resolved (N) | ' // &
          'F model R(h) 2U (N) | F / model | rise vs model | rise vs leading term | steps | steady | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|'
    end if
    do c = 1, size(configurations)
      spheroid_case%configuration = configurations(c)
      spheroid_case%cells = box_cells
      do k = 1, size(spheroid_gaps)
        spheroid_case%gap_cells = spheroid_gaps(k)
        call run_spheroid_squeeze(spheroid_case, row)
        if (k == 1) first = row
        if (is_root()) print spheroid_format, '| ', trim(configurations(c)), ' | ', row%cells(1), 'x', row%cells(2), &
            'x', row%cells(3), ' | ', spheroid_case%radius_cells, ' | ', spheroid_case%gap_cells, ' | ', &
            row%geometry%reduced_radius / row%resolved%cell, ' | ', row%geometry%radius1 / row%resolved%cell, ' | ', &
            row%resolved%force, ' | ', row%model_force, ' | ', row%resolved%force / row%model_force, ' | ', &
            trim(rise(k, row, first, row%model_force, first%model_force)), ' | ', trim(rise(k, row, first, row%leading_force, &
            first%leading_force)), &
            ' | ', row%resolved%steps, ' | ', trim(merge('yes', 'no ', row%resolved%steady)), ' | ', &
            row%resolved%wall_seconds, ' |'
      end do
    end do
  end subroutine spheroid_ladder

  !> (F(h) - F(h_1)) / (reference(h) - reference(h_1)) - 1 in per cent for row k of a spheroid
  !> ladder (first its widest gap); "(reference)" at h_1 itself.
  character(len=16) function rise(k, row, first, reference, reference_first)
    integer, intent(in) :: k
    type(spheroid_squeeze_result_t), intent(in) :: row, first
    real(wp), intent(in) :: reference, reference_first
    rise = '(reference)'
    if (k > 1) write(rise, '(sp,f7.1,a)') 100 * ((row%resolved%force - first%resolved%force) &
                                                / (reference - reference_first) - 1), '%'
  end function rise
end program bench_immersed_squeeze
