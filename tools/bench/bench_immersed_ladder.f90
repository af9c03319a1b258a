!> The immersed-boundary validation ladder (make validate; docs/studies/validation.md, "Immersed boundary"),
!> as Markdown tables. Each table is a section; the command-line arguments choose sections (none: all),
!> and a section may be narrowed as section:D/dx:coupling, e.g. `rotating:16:implicit` or
!> `dilute::explicit`.
!> - arrays: simple-cubic sphere arrays in Stokes flow at D/dx about 8, 12 and 16, for phi = 0.125 and
!>   0.064, implicit and explicit coupling, against Zick & Homsy (1982, J. Fluid Mech. 115, 13,
!>   Table 2: K = 4.292 at phi = 0.125, 2.810 at phi = 0.064), with the observed order of
!>   convergence between the coarsest and the finest grid, p = ln(e_8 / e_16) / ln(D_16 / D_8).
!> - dilute: the same at phi = 0.027 (K = 2.008, Zick & Homsy Table 2; Sangani & Acrivos 1982,
!>   Int. J. Multiphase Flow 8, 343, Eq. 4.11 gives 2.0077) at D/dx about 10, 12 and 16.
!> - rotating: a rotating sphere at D/dx = 8, 12 and 16 in boxes L/D = 2, 3, 4: the torque -T (it
!>   opposes the rotation) extrapolated to the unbounded box by a least-squares line in (a/L)^3
!>   against 8 pi mu a^3 Omega (Stokes).
!> - sweeps: Jacobi sweeps of the implicit ghost rows to 1e-12 for needles and disks (aspect 5) at
!>   random orientations and positions, 64^3 to 256^3 (immersed_sweep_survey).
!> - spheroids[:thin cells]: needle and disk (aspect 5) translating and rotating, two boxes, against
!>   Oberbeck/Perrin (rung 6); spheroid-transfer[:thin cells[:shape[:motion]]]: the box correction
!>   fitted on four boxes at 4.4 cells thin and carried to one box at the finer grid;
!>   spheroid-symmetry[:thin cells[:shape]]: torque of a translating needle and disk at the paper's
!>   thin-dimension resolution in tight boxes; spheroid-offsets[:thin cells[:shape[:motion[:count...]]]]:
!>   that torque over sub-cell offsets (with :ladder last, the ladder's offset as one more), momentum
!>   balance and face sum side by side;
!>   spheroid:shape:motion:thin:box:scheme:nu dt/dx^2: one run.
program bench_immersed_ladder
  use agglo_kinds, only: wp
  use sample_statistics, only: sorted_values
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use sphere_array_case, only: sphere_array_case_t, sphere_array_result_t, run_sphere_array, fit_power_series
  use immersed_sweep_survey, only: sweep_survey_t, run_sweep_survey
  use stokes_resistance, only: spheroid_resistance_coefficients
  use spheroid, only: make_spheroid, spheroid_t
  implicit none
  character(len=8), parameter :: couplings(2) = [character(len=8) :: 'implicit', 'explicit']
  character(len=256) :: argument
  integer :: a

  call parallel_start()
  if (command_argument_count() == 0) then
    call run_section('arrays')
    call run_section('dilute')
    call run_section('rotating')
    call run_section('sweeps')
    call run_section('spheroids')
    call run_section('spheroids:6')
    call run_section('spheroid-symmetry')
    call run_section('spheroid-offsets')
    call run_section('spheroid-offsets:15:needle::4:crank_nicolson:5')
    call run_section('spheroid-offsets:8.8:disk::4:crank_nicolson:5')
    ! 1.27 and 1.6 times the paper's thin dimension (docs/studies/validation.md, rung 6): 8 offsets and the
    ! ladder's, 16 for the needle across its axis at 19 cells and for both shapes at 1.6 times.
    call run_section('spheroid-offsets:19:needle:along:8:crank_nicolson:5:2:ladder')
    call run_section('spheroid-offsets:19:needle:across:16:crank_nicolson:5:2:ladder')
    call run_section('spheroid-offsets:11.2:disk::8:crank_nicolson:5:2:ladder')
    call run_section('spheroid-offsets:14:disk::16:crank_nicolson:5:2:ladder')
    call run_section('spheroid-offsets:24:needle::16:crank_nicolson:5:2:ladder')
    call run_section('spheroid-transfer')
  else
    do a = 1, command_argument_count()
      call get_command_argument(a, argument)
      call run_section(trim(argument))
    end do
  end if
  call parallel_stop()

contains

  !> One section, narrowed by the optional ":D/dx:coupling" suffixes.
  subroutine run_section(spec)
    character(len=*), intent(in) :: spec
    character(len=64) :: name, only_coupling
    real(wp) :: only_diameter
    integer :: first, second, status
    first = index(spec, ':')
    name = spec
    only_diameter = 0
    only_coupling = ''
    if (first > 0) name = spec(:first - 1)
    if (first > 0 .and. trim(name) /= 'spheroid' .and. trim(name) /= 'spheroid-transfer' .and. &
        trim(name) /= 'spheroid-symmetry' .and. trim(name) /= 'spheroid-offsets') then
      second = index(spec(first + 1:), ':')
      if (second > 0) then
        only_coupling = spec(first + second + 1:)
        second = first + second
      else
        second = len_trim(spec) + 1
      end if
      if (second - 1 > first) then
        read(spec(first + 1:second - 1), *, iostat=status) only_diameter
        if (status /= 0) then
          if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': D/dx is not a number'
          error stop 1
        end if
      end if
    end if
    select case (trim(name))
    case ('arrays')
      call array_table([0.125_wp, 0.064_wp], [4.292_wp, 2.810_wp], [8.0_wp, 12.0_wp, 16.0_wp], only_diameter, &
                       only_coupling)
    case ('dilute')
      call array_table([0.027_wp], [2.008_wp], [10.0_wp, 12.0_wp, 16.0_wp], only_diameter, only_coupling)
    case ('rotating')
      call rotating_table([8, 12, 16], only_diameter, only_coupling)
    case ('sweeps')
      call sweep_table()
    case ('spheroids')
      ! spheroids:T: thinnest dimension T cells (default 4.4), the boxes scaled with it.
      call spheroid_table(merge(4.4_wp, only_diameter, only_diameter <= 0), only_coupling)
    case ('spheroid')
      call spheroid_single(spec)
    case ('spheroid-transfer')
      call spheroid_transfer(spec)
    case ('spheroid-symmetry')
      call spheroid_symmetry(spec)
    case ('spheroid-offsets')
      call spheroid_offsets(spec)
    case default
      if (is_root()) print '(a)', 'bench_immersed_ladder: unknown section '''//trim(spec)// &
          '''; allowed: arrays, dilute, rotating, sweeps, spheroids (each optionally :D/dx:coupling; ' // &
          'for spheroids :thin cells:coupling), spheroid:shape:motion:thin cells:box cells:scheme:nu dt/dx^2, ' // &
          'spheroid-transfer[:thin cells[:shape[:motion]]], spheroid-symmetry[:thin cells[:shape]], ' // &
          'spheroid-offsets[:thin cells[:shape[:motion[:count[:scheme[:nu dt/dx^2[:level[:ladder]]]]]]]]'
      error stop 1
    end select
  end subroutine run_section

  logical function chosen(diameter, coupling, only_diameter, only_coupling)
    real(wp), intent(in) :: diameter, only_diameter
    character(len=*), intent(in) :: coupling, only_coupling
    chosen = (only_diameter == 0 .or. abs(diameter - only_diameter) < 0.5_wp) .and. &
             (len_trim(only_coupling) == 0 .or. trim(coupling) == trim(only_coupling))
  end function chosen

  !> Sphere arrays against Zick & Homsy, with the observed order between the first and last D/dx.
  subroutine array_table(fractions, references, diameters, only_diameter, only_coupling)
    real(wp), intent(in) :: fractions(:), references(:), diameters(:), only_diameter
    character(len=*), intent(in) :: only_coupling
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    real(wp) :: errors(size(diameters)), sizes(size(diameters))
    integer :: f, c, d, n
    if (is_root()) then
      print '(a)', '| phi | coupling | cells | D/dx | K | K (Z&H) | error | steps | sweeps mean/max | slip | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|'
    end if
    n = size(diameters)
    do f = 1, size(fractions)
      do c = 1, size(couplings)
        errors = 0
        do d = 1, n
          if (.not. chosen(diameters(d), couplings(c), only_diameter, only_coupling)) cycle
          case%volume_fraction = fractions(f)
          case%coupling = couplings(c)
          case%cells = nint(diameters(d) / (6.0_wp * fractions(f) / acos(-1.0_wp))**(1.0_wp / 3.0_wp))
          case%max_steps = 80000
          if (fractions(f) < 0.05_wp) case%steady_tolerance = 1.0e-8_wp
          call run_sphere_array(case, result)
          errors(d) = result%drag_coefficient / references(f) - 1.0_wp
          sizes(d) = result%diameter_cells
          if (is_root()) print '(a,f5.3,a,a,a,i0,a,f5.2,a,f6.4,a,f5.3,a,f7.2,a,i0,a,f4.1,a,i0,a,es8.1,a,f6.1,a,a)', &
              '| ', fractions(f), ' | ', trim(couplings(c)), ' | ', case%cells, '^3 | ', result%diameter_cells, ' | ', &
              result%drag_coefficient, ' | ', references(f), ' | ', 100 * errors(d), '% | ', result%steps, ' | ', &
              result%mean_sweeps, '/', result%max_sweeps, ' | ', result%slip, ' | ', result%wall_seconds, &
              merge(' |         ', ' unsteady |', result%steady)
        end do
        if (is_root() .and. errors(1) /= 0 .and. errors(n) /= 0) &
          print '(a,f5.3,a,a,a,f5.2)', '|   | observed order, phi = ', fractions(f), ', ', trim(couplings(c)), &
              ': ', log(abs(errors(1)) / abs(errors(n))) / log(sizes(n) / sizes(1))
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine array_table

  !> Rotating sphere in boxes L/D = 2, 3, 4 at each D/dx, extrapolated in (a/L)^3.
  subroutine rotating_table(resolutions, only_diameter, only_coupling)
    integer, intent(in) :: resolutions(:)
    real(wp), intent(in) :: only_diameter
    character(len=*), intent(in) :: only_coupling
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    real(wp) :: x(3), y(3), slope, unbounded
    integer :: r, c, d
    if (is_root()) then
      print '(a)', '| coupling | cells | D/dx | a/L | T / (8 pi mu a^3 Omega) | steps | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|'
    end if
    do r = 1, size(resolutions)
      do c = 1, size(couplings)
        if (.not. chosen(real(resolutions(r), wp), couplings(c), only_diameter, only_coupling)) cycle
        do d = 1, 3
          case%rotating = .true.
          case%coupling = couplings(c)
          case%cells = resolutions(r) * (d + 1)
          case%volume_fraction = acos(-1.0_wp) / 6.0_wp / real(d + 1, wp)**3
          case%max_steps = 40000
          call run_sphere_array(case, result)
          x(d) = result%radius_over_box**3
          y(d) = -result%torque(3) / result%stokes_torque
          if (is_root()) print '(a,a,a,i0,a,f5.2,a,f6.4,a,f8.5,a,i0,a,f6.1,a,a)', '| ', trim(couplings(c)), ' | ', &
              case%cells, '^3 | ', result%diameter_cells, ' | ', result%radius_over_box, ' | ', y(d), ' | ', &
              result%steps, ' | ', result%wall_seconds, merge(' |         ', ' unsteady |', result%steady)
        end do
        slope = (sum(x * y) - sum(x) * sum(y) / 3) / (sum(x**2) - sum(x)**2 / 3)
        unbounded = (sum(y) - slope * sum(x)) / 3
        if (is_root()) print '(a,a,a,i0,a,f8.5,a,f7.2,a,f5.2,a)', '|   | ', trim(couplings(c)), ', D/dx = ', &
            resolutions(r), ': extrapolated to a/L = 0: ', unbounded, ' (error ', 100 * (unbounded - 1), &
            '%), slope ', slope, ' |'
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine rotating_table

  !> Ghost-row sweeps for random needles and disks.
  subroutine sweep_table()
    type(sweep_survey_t) :: survey
    ! Volume-equivalent radius 0.1 mm at 64^3 to 256^3, then the paper's 50 um at 128^3 and 256^3.
    integer, parameter :: grids(5) = [64, 128, 256, 128, 256], placements(5) = [16, 8, 4, 8, 4]
    real(wp), parameter :: radii(5) = [0.1e-3_wp, 0.1e-3_wp, 0.1e-3_wp, 0.05e-3_wp, 0.05e-3_wp]
    character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
    integer :: g, s
    if (is_root()) then
      print '(a)', '| shape | r, mm | cells | thin dimension, cells | placements | ghosts per placement | ' // &
          'sweeps mean/max | residual max | classification s | imposition s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|'
    end if
    do g = 1, size(grids)
      do s = 1, size(shapes)
        survey%shape = shapes(s)
        survey%cells = grids(g)
        survey%placements = placements(g)
        survey%radius = radii(g)
        call run_sweep_survey(survey)
        if (is_root()) print '(a,a,a,f5.3,a,i0,a,f5.2,a,i0,a,f8.0,a,f4.1,a,i0,a,es8.1,a,f7.3,a,f7.3,a)', '| ', &
            trim(shapes(s)), ' | ', 1.0e3_wp * radii(g), ' | ', grids(g), '^3 | ', survey%thin_cells, ' | ', &
            survey%placements, ' | ', &
            survey%mean_ghosts, ' | ', survey%mean_sweeps, '/', survey%max_sweeps, ' | ', survey%max_residual, &
            ' | ', survey%classify_seconds, ' | ', survey%impose_seconds, ' |'
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine sweep_table
  !> Needle and disk (aspect 5, thin_cells thin: 4.4 by default) translating along and across the
  !> axis (fixed body, driven box, F = f L^3 against the superficial velocity U) and rotating about
  !> and across it, in boxes of 32^3 and 40^3 (scaled with thin_cells/4.4), against Oberbeck/Perrin
  !> (stokes_resistance). Translation: the periodic array's mobility is
  !> 6 pi mu r U/F = 1/c - 2.837 r/L + C (r/L)^3 (Hasimoto 1959, J. Fluid Mech. 5, 317: the O(1/L)
  !> term does not depend on the body's shape), solved for c and C from the two boxes. Rotation: a
  !> line in (r/L)^3 through the two boxes. Torque of the translating body over F r (symmetry), at
  !> the offset of the tables and with the centre on a grid symmetry point. Translation stops on the
  !> Aitken estimate of U (sphere_array_case, aitken_window), rotation when the torque changes by
  !> less than 1e-7 per step (the remaining error is below 1e-4).
  subroutine spheroid_table(thin_cells, only_coupling)
    real(wp), intent(in) :: thin_cells
    character(len=*), intent(in) :: only_coupling
    character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
    character(len=16), parameter :: motions(4) = [character(len=16) :: 'translate along', 'translate across', &
                                                  'rotate about', 'rotate across']
    real(wp), parameter :: hasimoto = 2.837_wp
    integer :: boxes(2)
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    type(spheroid_t) :: unit_shape
    real(wp) :: reference(4), x(2), y(2), expected, measured, extrapolated, cubic, torque_ratio
    integer :: s, m, b, c
    boxes = nint([32.0_wp, 40.0_wp] * thin_cells / 4.4_wp)
    if (is_root()) then
      print '(a)', '| shape | motion | coupling | cells | r/dx | r/L | raw coefficient | Oberbeck/Perrin | ' // &
          'torque/(F r) | steps | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|'
    end if
    do c = 1, size(couplings)
      if (len_trim(only_coupling) > 0 .and. trim(couplings(c)) /= trim(only_coupling)) cycle
      do s = 1, size(shapes)
        unit_shape = make_spheroid(trim(shapes(s)), 1.0_wp, 1.0_wp)
        reference = spheroid_resistance_coefficients(unit_shape%a, unit_shape%b)
        do m = 1, size(motions)
          expected = reference(m)
          do b = 1, size(boxes)
            case = spheroid_case(shapes(s), m, thin_cells, boxes(b), 'explicit', 0.06_wp)
            case%coupling = couplings(c)
            call run_sphere_array(case, result)
            x(b) = result%radius_over_box
            call spheroid_coefficient(result, m, case, measured, torque_ratio)
            y(b) = measured
            if (m <= 2) y(b) = 1.0_wp / measured
            if (is_root()) print '(a,a,a,a,a,a,a,i0,a,f5.2,a,f6.4,a,f7.4,a,f7.4,a,es8.1,a,i0,a,f6.1,a,a)', '| ', &
                trim(shapes(s)), ' | ', trim(motions(m)), ' | ', trim(couplings(c)), ' | ', boxes(b), '^3 | ', &
                case%radius_cells, ' | ', x(b), ' | ', measured, ' | ', expected, ' | ', torque_ratio, ' | ', &
                result%steps, ' | ', result%wall_seconds, merge(' |         ', ' unsteady |', result%steady)
          end do
          if (m <= 2) then
            ! Symmetry: the same body with its centre on a grid symmetry point (a cell-face corner).
            case%cells = boxes(1)
            case%offset_cells = 0
            call run_sphere_array(case, result)
            if (is_root()) print '(a,a,a,a,a,i0,a,es8.1,a,i0,a,f6.1,a)', '|   | ', trim(shapes(s)), ', ', &
                trim(motions(m)), ', centre on a grid symmetry point, ', boxes(1), '^3: torque/(F r) ', &
                norm2(result%torque) / (result%drive(1) * result%radius), ', ', result%steps, ' steps, ', &
                result%wall_seconds, ' s |'
            ! y = 1/c - hasimoto x + C x^3 through both boxes.
            cubic = ((y(1) + hasimoto * x(1)) - (y(2) + hasimoto * x(2))) / (x(1)**3 - x(2)**3)
            extrapolated = 1.0_wp / (y(1) + hasimoto * x(1) - cubic * x(1)**3)
          else
            cubic = (y(1) - y(2)) / (x(1)**3 - x(2)**3)
            extrapolated = y(1) - cubic * x(1)**3
          end if
          if (is_root()) print '(a,a,a,a,a,a,a,f7.4,a,f7.4,a,f6.2,a,f7.2,a)', '|   | ', trim(shapes(s)), ', ', &
              trim(motions(m)), ', ', trim(couplings(c)), ': extrapolated ', extrapolated, ' against ', expected, &
              ' (error ', 100 * (extrapolated / expected - 1), '%), (r/L)^3 coefficient ', cubic, ' |'
        end do
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine spheroid_table

  !> The spheroid case of the ladder: shape 'needle' or 'disk' (aspect 5), motion m (1 translate
  !> along the axis, 2 across it, 3 rotate about it, 4 across it), thin_cells across the thinnest
  !> dimension, a box of `cells`, the viscous scheme and nu dt/dx^2. The Aitken window (translation)
  !> is 1000 steps at nu dt/dx^2 = 0.06, the same simulated time at other steps (at least 10).
  type(sphere_array_case_t) function spheroid_case(shape, m, thin_cells, cells, scheme, number) result(case)
    character(len=*), intent(in) :: shape, scheme
    integer, intent(in) :: m, cells
    real(wp), intent(in) :: thin_cells, number
    type(spheroid_t) :: unit_shape
    unit_shape = make_spheroid(trim(shape), 1.0_wp, 1.0_wp)
    case = sphere_array_case_t()
    case%coupling = 'implicit'
    case%shape = shape
    case%cells = cells
    case%radius_cells = thin_cells / (2.0_wp * min(unit_shape%a, unit_shape%b))
    case%viscous_scheme = scheme
    case%viscous_number = number
    case%steady_tolerance = 1.0e-7_wp
    case%aitken_window = max(10, nint(1000 * 0.06_wp / number))
    case%max_steps = 60000
    case%rotating = m >= 3
    case%axis = [1.0_wp, 0.0_wp, 0.0_wp]
    if (m == 2) case%axis = [0.0_wp, 1.0_wp, 0.0_wp]
    case%rotation_axis = [1.0_wp, 0.0_wp, 0.0_wp]
    if (m == 4) case%rotation_axis = [0.0_wp, 0.0_wp, 1.0_wp]
  end function spheroid_case

  !> The resistance coefficient of a spheroid run: F/(6 pi mu r U) (translation, F = f L^3, U the
  !> superficial velocity) or -T.Omega/(8 pi mu r^3 |Omega|^2) (rotation); torque_ratio = |T|/(F r) of
  !> a translation (0 for a rotation).
  subroutine spheroid_coefficient(result, m, case, coefficient, torque_ratio)
    type(sphere_array_result_t), intent(in) :: result
    integer, intent(in) :: m
    type(sphere_array_case_t), intent(in) :: case
    real(wp), intent(out) :: coefficient, torque_ratio
    real(wp) :: r
    r = result%radius
    torque_ratio = 0
    if (m <= 2) then
      coefficient = result%drive(1) / (6.0_wp * acos(-1.0_wp) * result%dynamic_viscosity * r * result%superficial_velocity)
      torque_ratio = norm2(result%torque) / (result%drive(1) * r)
    else
      coefficient = -dot_product(result%torque, case%rotation_axis) / norm2(case%rotation_axis) / &
                    (8.0_wp * acos(-1.0_wp) * result%dynamic_viscosity * r**3 * result%angular_speed)
    end if
  end subroutine spheroid_coefficient

  !> One spheroid run,
  !> spheroid:shape:motion:thin cells:box cells:scheme:nu dt/dx^2[:offset[:nx:ny:nz[:level[:steady tolerance]]]],
  !> motion one of along, across, about, tumble (rotate across the axis), scheme explicit or
  !> crank_nicolson; offset 'centred' puts the centre on a grid symmetry point, 'offset' (default) at
  !> the ladder's sub-cell offset, or ox,oy,oz in cells; nx:ny:nz a non-cubic box at the spacing of
  !> the box cells^3 (0:0:0 the cubic box); level the icosphere level of a face-sum torque printed
  !> beside the momentum one (translations; empty: none); steady tolerance the relative change per step
  !> that stops the run (default 1e-7), which also prints the approach of the coefficient (print_tail).
  subroutine spheroid_single(spec)
    character(len=*), intent(in) :: spec
    character(len=*), parameter :: motion_names(4) = [character(len=6) :: 'along', 'across', 'about', 'tumble']
    character(len=32) :: fields(13)
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    type(spheroid_t) :: unit_shape
    real(wp) :: thin, number, coefficient, torque_ratio, reference(4), surface_ratio
    integer :: box_cells(3)
    character(len=32) :: box_label
    integer :: n, m, cells, status(6)
    call split_fields(spec, fields, n)
    m = findloc(motion_names, trim(fields(3)), dim=1)
    status = 1
    if (n >= 7) then
      read(fields(4), *, iostat=status(1)) thin
      read(fields(5), *, iostat=status(2)) cells
      read(fields(7), *, iostat=status(3)) number
    end if
    if (n >= 11) then
      read(fields(9), *, iostat=status(4)) case%box_cells(1)
      read(fields(10), *, iostat=status(5)) case%box_cells(2)
      read(fields(11), *, iostat=status(6)) case%box_cells(3)
    else
      status(4:6) = 0
    end if
    if (n < 7 .or. m == 0 .or. any(status /= 0) .or. (trim(fields(2)) /= 'needle' .and. trim(fields(2)) /= 'disk')) then
      if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': expected spheroid:needle|disk:' // &
          'along|across|about|tumble:thin cells:box cells:explicit|crank_nicolson:nu dt/dx^2[:centred|offset[:nx:ny:nz]]'
      error stop 1
    end if
    box_cells = case%box_cells
    case = spheroid_case(fields(2), m, thin, cells, fields(6), number)
    case%box_cells = box_cells
    if (n >= 8) then
      if (trim(fields(8)) == 'centred') then
        case%offset_cells = 0
      else if (trim(fields(8)) /= 'offset' .and. len_trim(fields(8)) > 0) then
        read(fields(8), *, iostat=status(1)) case%offset_cells
        if (status(1) /= 0) then
          if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': the offset is centred, offset ' // &
              'or three numbers ox,oy,oz (cells)'
          error stop 1
        end if
      end if
    end if
    if (n >= 13) then
      read(fields(13), *, iostat=status(1)) case%steady_tolerance
      if (status(1) /= 0 .or. case%steady_tolerance <= 0) then
        if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': the steady tolerance is a number > 0'
        error stop 1
      end if
      case%history_every = 10
    end if
    if (n >= 12 .and. len_trim(fields(12)) > 0) then
      read(fields(12), *, iostat=status(1)) case%surface_level
      if (status(1) /= 0 .or. case%surface_level < 0) then
        if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': the surface level is an icosphere ' // &
            'level >= 0'
        error stop 1
      end if
    end if
    call run_sphere_array(case, result)
    call spheroid_coefficient(result, m, case, coefficient, torque_ratio)
    surface_ratio = 0
    if (m <= 2) surface_ratio = norm2(result%surface_torque) / (result%drive(1) * result%radius)
    unit_shape = make_spheroid(trim(fields(2)), 1.0_wp, 1.0_wp)
    reference = spheroid_resistance_coefficients(unit_shape%a, unit_shape%b)
    write(box_label, '(i0,a)') cells, '^3'
    if (all(case%box_cells > 0)) write(box_label, '(i0,a,i0,a,i0)') case%box_cells(1), 'x', case%box_cells(2), 'x', &
                                                                     case%box_cells(3)
    if (is_root()) print '(a,a,a,a,a,f5.2,a,a,a,a,a,f5.2,a,f5.2,a,f7.5,a,f8.5,a,f7.4,a,es8.1,a,i0,a,f5.1,a,f7.1,a,a)', &
        '| ', trim(fields(2)), ' | ', trim(fields(3)), ' | ', thin, ' | ', trim(box_label), ' | ', trim(fields(6)), ' | ', &
        number, ' | ', result%diameter_cells / 2, &
        ' | ', result%radius_over_box, ' | ', coefficient, ' | ', reference(m), ' | ', torque_ratio, ' | ', &
        result%steps, ' | ', result%mean_sweeps, ' | ', result%wall_seconds, merge(' |         ', ' unsteady |', result%steady)
    if (is_root() .and. case%surface_level >= 0 .and. m <= 2) print '(a,i0,a,es8.1)', &
        '|   | face-sum torque/(F r), icosphere level ', case%surface_level, ': ', surface_ratio
    ! With a steady tolerance given: the coefficient at the last samples 10 steps apart, and their
    ! Aitken extrapolation (the slowest mode's geometric tail; a rotation's torque, or a
    ! translation's torque over U).
    if (is_root() .and. case%history_every > 0) call print_tail(result, m, case)
  end subroutine spheroid_single

  !> The coefficient of a rotation (the torque about Omega) at the last three history samples and
  !> the Aitken extrapolation of the geometric tail, x3 - (x3 - x2)^2 / ((x3 - x2) - (x2 - x1)): what
  !> a run stopped at a loose steady tolerance still misses.
  subroutine print_tail(result, m, case)
    type(sphere_array_result_t), intent(in) :: result
    integer, intent(in) :: m
    type(sphere_array_case_t), intent(in) :: case
    real(wp) :: x(3), limit
    integer :: last
    last = size(result%history, 2)
    if (m <= 2 .or. last < 3) return
    x = -matmul(case%rotation_axis / norm2(case%rotation_axis), result%history(3:5, last - 2:last)) / &
        (8.0_wp * acos(-1.0_wp) * result%dynamic_viscosity * result%radius**3 * result%angular_speed)
    limit = x(3)
    if (abs((x(3) - x(2)) - (x(2) - x(1))) > 0) limit = x(3) - (x(3) - x(2))**2 / ((x(3) - x(2)) - (x(2) - x(1)))
    print '(a,3(i0,a,f9.6,a),a,f9.6,a)', '|   | coefficient at steps ', nint(result%history(1, last - 2)), ': ', x(1), &
        ', ', nint(result%history(1, last - 1)), ': ', x(2), ', ', nint(result%history(1, last)), ': ', x(3), &
        ';', ' Aitken limit ', limit, ' |'
  end subroutine print_tail

  !> The box correction carried from a coarse grid to a fine one (docs/studies/validation.md, rung 6),
  !> spheroid-transfer[:thin cells[:shape[:motion]]], default 8.8 cells, both shapes, all four motions.
  !> The continuum box correction at a given r/L does not depend on the grid, so it is measured on the
  !> coarse grid (4.4 cells thin) in boxes of 32, 40, 48 and 64 cells and fitted in the mobility
  !> y = 1/coefficient: y + 2.837 r/L = y_inf + C3 (r/L)^3 + C5 (r/L)^5 for a translation (Hasimoto
  !> 1959, J. Fluid Mech. 5, 317: the O(1/L) term of the lattice, shape-independent),
  !> y = y_inf + C3 (r/L)^3 + C5 (r/L)^5 for a rotation (the rotlet's periodic images turn the fluid
  !> at the body by -T/(6 mu L^3), the x^3 term; a stresslet adds to it). On the fine grid one box
  !> at about the r/L of the coarse 32^3 (32 thin/4.4 cells, rounded to an even count) and
  !> y_inf(fine) = y(fine) - [y_fit(r/L) - y_inf].
  !> Crank-Nicolson at nu dt/dx^2 = 5 throughout (its steady-state shift is the same in every box:
  !> it cancels in the correction; it is measured against explicit diffusion in the docs). Also printed:
  !> y_inf from a line in (r/L)^3 through the three largest boxes, the fit's sensitivity.
  subroutine spheroid_transfer(spec)
    character(len=*), intent(in) :: spec
    character(len=*), parameter :: motion_names(4) = [character(len=6) :: 'along', 'across', 'about', 'tumble']
    character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
    real(wp), parameter :: hasimoto = 2.837_wp, coarse_thin = 4.4_wp, number = 5.0_wp
    integer, parameter :: boxes(4) = [32, 40, 48, 64]
    character(len=32) :: fields(4)
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    type(spheroid_t) :: unit_shape
    real(wp) :: thin, x(size(boxes)), y(size(boxes)), series(3), line(2), reference(4), coefficient, torque_ratio
    real(wp) :: lattice, coarse_inf, line_inf, fine_x, fine_y, fine_inf
    integer :: n, s, m, b, status, fine_box
    call split_fields(spec, fields, n)
    thin = 8.8_wp
    status = 0
    if (n >= 2 .and. len_trim(fields(2)) > 0) read(fields(2), *, iostat=status) thin
    if (status /= 0 .or. thin <= 0) then
      if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': thin cells is not a positive number'
      error stop 1
    end if
    ! Even, like the coarse boxes (the body's centre is then a cell corner plus the offset in every box).
    fine_box = 2 * nint(boxes(1) * thin / (2 * coarse_thin))
    if (is_root()) then
      print '(a)', '| shape | motion | thin cells | cells | r/L | raw coefficient | Oberbeck/Perrin | torque/(F r) | ' // &
          'steps | iterations mean | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|'
    end if
    do s = 1, size(shapes)
      if (n >= 3 .and. len_trim(fields(3)) > 0 .and. trim(fields(3)) /= trim(shapes(s))) cycle
      unit_shape = make_spheroid(trim(shapes(s)), 1.0_wp, 1.0_wp)
      reference = spheroid_resistance_coefficients(unit_shape%a, unit_shape%b)
      do m = 1, size(motion_names)
        if (n >= 4 .and. len_trim(fields(4)) > 0 .and. trim(fields(4)) /= trim(motion_names(m))) cycle
        lattice = merge(hasimoto, 0.0_wp, m <= 2)
        do b = 1, size(boxes) + 1
          if (b <= size(boxes)) then
            case = spheroid_case(shapes(s), m, coarse_thin, boxes(b), 'crank_nicolson', number)
          else
            case = spheroid_case(shapes(s), m, thin, fine_box, 'crank_nicolson', number)
          end if
          call run_sphere_array(case, result)
          call spheroid_coefficient(result, m, case, coefficient, torque_ratio)
          if (b <= size(boxes)) then
            x(b) = result%radius_over_box
            y(b) = 1.0_wp / coefficient + lattice * x(b)
          else
            fine_x = result%radius_over_box
            fine_y = 1.0_wp / coefficient + lattice * fine_x
          end if
          if (is_root()) print '(a,a,a,a,a,f5.2,a,i0,a,f7.5,a,f8.5,a,f7.4,a,es8.1,a,i0,a,f5.1,a,f7.1,a,a)', '| ', &
              trim(shapes(s)), ' | ', trim(motion_names(m)), ' | ', merge(coarse_thin, thin, b <= size(boxes)), ' | ', &
              case%cells, '^3 | ', result%radius_over_box, ' | ', &
              coefficient, ' | ', reference(m), ' | ', torque_ratio, ' | ', result%steps, ' | ', result%mean_sweeps, &
              ' | ', result%wall_seconds, merge(' |         ', ' unsteady |', result%steady)
        end do
        call fit_power_series(x, y, [0.0_wp, 3.0_wp, 5.0_wp], series)
        call fit_power_series(x(2:), y(2:), [0.0_wp, 3.0_wp], line)
        coarse_inf = 1.0_wp / series(1)
        line_inf = 1.0_wp / line(1)
        ! The fine grid's y minus the coarse box correction at the fine box's r/L.
        fine_inf = 1.0_wp / (fine_y - (series(2) * fine_x**3 + series(3) * fine_x**5))
        if (is_root()) print '(a,a,a,a,a,f7.4,a,f6.2,a,f7.4,a,f6.2,a,f8.2,a,f9.1,a,f5.2,a,f7.4,a,f6.2,a)', '|   | ', &
            trim(shapes(s)), ', ', trim(motion_names(m)), ': coarse extrapolated ', coarse_inf, ' (', &
            100 * (coarse_inf / reference(m) - 1), '%; line through the 3 largest boxes ', line_inf, ' (', &
            100 * (line_inf / reference(m) - 1), '%)); C3 ', series(2), ', C5 ', series(3), '; fine (', thin, &
            ' cells thin) corrected ', fine_inf, ' (error ', 100 * (fine_inf / reference(m) - 1), '%) |'
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine spheroid_transfer

  !> Torque of a translating needle and disk (axis along and across the drive) at a sub-cell offset,
  !> spheroid-symmetry[:thin cells[:shape]] (default the paper's thin dimension: needle 15, disk 8.8
  !> cells), in a tight box: the torque vanishes by symmetry in any periodic lattice of the body, so
  !> the box only has to hold it (2 nint(half extent) + 8 cells along each axis). Explicit diffusion,
  !> Aitken stop as in the ladder. Bound: 1e-3 F r (rung 6, docs/studies/validation.md).
  subroutine spheroid_symmetry(spec)
    character(len=*), intent(in) :: spec
    character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
    real(wp), parameter :: paper_thin(2) = [15.0_wp, 8.8_wp]
    character(len=32) :: fields(3)
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    real(wp) :: thin, only_thin, coefficient, torque_ratio
    integer :: n, s, m, status
    call split_fields(spec, fields, n)
    only_thin = 0
    status = 0
    if (n >= 2 .and. len_trim(fields(2)) > 0) read(fields(2), *, iostat=status) only_thin
    if (status /= 0 .or. only_thin < 0) then
      if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': thin cells is not a positive number'
      error stop 1
    end if
    if (is_root()) then
      print '(a)', '| shape | motion | thin cells | box cells | torque/(F r) | bound | steps | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|'
    end if
    do s = 1, size(shapes)
      if (n >= 3 .and. len_trim(fields(3)) > 0 .and. trim(fields(3)) /= trim(shapes(s))) cycle
      thin = merge(paper_thin(s), only_thin, only_thin <= 0)
      do m = 1, 2
        case = tight_box_case(shapes(s), m, thin, 'explicit', 0.06_wp)
        call run_sphere_array(case, result)
        call spheroid_coefficient(result, m, case, coefficient, torque_ratio)
        if (is_root()) print '(a,a,a,a,a,f5.2,a,i0,a,i0,a,i0,a,es8.1,a,i0,a,f7.1,a,a)', '| ', trim(shapes(s)), ' | ', &
            merge('translate along ', 'translate across', m == 1), ' | ', thin, ' | ', case%box_cells(1), 'x', &
            case%box_cells(2), 'x', case%box_cells(3), ' | ', torque_ratio, ' | 1e-3 | ', result%steps, ' | ', &
            result%wall_seconds, merge(' |         ', ' unsteady |', result%steady)
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine spheroid_symmetry

  !> The translating spheroid (m = 1 axis along the drive, 2 across) in the tight box of the
  !> symmetry checks: 2 nint(half extent) + 8 cells along each axis, the sub-cell offset of the ladder.
  type(sphere_array_case_t) function tight_box_case(shape, m, thin, scheme, number) result(case)
    character(len=*), intent(in) :: shape, scheme
    integer, intent(in) :: m
    real(wp), intent(in) :: thin, number
    type(spheroid_t) :: unit_shape
    real(wp) :: half(3)
    unit_shape = make_spheroid(trim(shape), 1.0_wp, 1.0_wp)
    case = spheroid_case(shape, m, thin, 32, scheme, number)
    ! Half extents in cells along x, y, z of the body's axis along x (m = 1) or y (m = 2).
    half = case%radius_cells * unit_shape%b
    half(m) = case%radius_cells * unit_shape%a
    case%box_cells = 2 * nint(half) + 8
  end function tight_box_case

  !> The torque of a translating needle and disk over sub-cell offsets (docs/studies/validation.md, rung 6),
  !> spheroid-offsets[:thin cells[:shape[:motion[:count[:scheme[:nu dt/dx^2[:level[:ladder]]]]]]]],
  !> defaults 4.4 cells, both shapes, along and across, 8 offsets, explicit, 0.06, icosphere level 2. The
  !> offsets are the first `count` points of the R3 low-discrepancy sequence (Roberts 2018: the
  !> fractional parts of 1/2 + k (1/g, 1/g^2, 1/g^3), g^4 = g + 1) minus 1/2, spread evenly over the
  !> cell, and with `ladder` the ladder's offset (0.13, 0.27, 0.41) as one more (the offset of the
  !> spheroids and spheroid-symmetry tables); the tight box of spheroid-symmetry. Per offset the
  !> momentum-balance and the face-sum torque over F r and the relative change of T/U over the last
  !> sampling window (the steadiness of the torque); per case their median, root mean square and
  !> largest value.
  subroutine spheroid_offsets(spec)
    character(len=*), intent(in) :: spec
    character(len=*), parameter :: motion_names(2) = [character(len=6) :: 'along', 'across']
    character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
    real(wp), parameter :: plastic = 1.22074408460575947536_wp
    character(len=32) :: fields(9), scheme
    type(sphere_array_case_t) :: case
    type(sphere_array_result_t) :: result
    real(wp) :: thin, number, coefficient, alpha(3), drift
    real(wp), allocatable :: momentum(:), surface(:)
    integer :: n, s, m, k, count, samples, level, last, status(4)
    logical :: with_ladder
    call split_fields(spec, fields, n)
    thin = 4.4_wp; count = 8; scheme = 'explicit'; number = 0.06_wp; level = 2
    status = 0
    if (n >= 2 .and. len_trim(fields(2)) > 0) read(fields(2), *, iostat=status(1)) thin
    if (n >= 5 .and. len_trim(fields(5)) > 0) read(fields(5), *, iostat=status(2)) count
    if (n >= 6 .and. len_trim(fields(6)) > 0) scheme = fields(6)
    if (n >= 7 .and. len_trim(fields(7)) > 0) read(fields(7), *, iostat=status(3)) number
    if (n >= 8 .and. len_trim(fields(8)) > 0) read(fields(8), *, iostat=status(4)) level
    with_ladder = n >= 9 .and. trim(fields(9)) == 'ladder'
    if (any(status /= 0) .or. thin <= 0 .or. count < 1 .or. number <= 0 .or. level < 0 .or. &
        (trim(scheme) /= 'explicit' .and. trim(scheme) /= 'crank_nicolson') .or. &
        (n >= 9 .and. .not. with_ladder .and. len_trim(fields(9)) > 0)) then
      if (is_root()) print '(a)', 'bench_immersed_ladder: '''//trim(spec)//''': expected spheroid-offsets' // &
          '[:thin cells > 0[:needle|disk[:along|across[:count >= 1[:explicit|crank_nicolson[:nu dt/dx^2 > 0' // &
          '[:icosphere level >= 0[:ladder]]]]]]]]'
      error stop 1
    end if
    alpha = [1.0_wp / plastic, 1.0_wp / plastic**2, 1.0_wp / plastic**3]
    samples = count + merge(1, 0, with_ladder)
    allocate(momentum(samples), surface(samples))
    if (is_root()) then
      print '(a)', '| shape | motion | thin cells | box cells | offset (cells) | torque/(F r) momentum | ' // &
          'torque/(F r) face sum | T/U change, last window | steps | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|'
    end if
    do s = 1, size(shapes)
      if (n >= 3 .and. len_trim(fields(3)) > 0 .and. trim(fields(3)) /= trim(shapes(s))) cycle
      do m = 1, size(motion_names)
        if (n >= 4 .and. len_trim(fields(4)) > 0 .and. trim(fields(4)) /= trim(motion_names(m))) cycle
        do k = 1, samples
          case = tight_box_case(shapes(s), m, thin, scheme, number)
          ! Past `count`: the case's own offset, the ladder's (0.13, 0.27, 0.41).
          if (k <= count) case%offset_cells = modulo(0.5_wp + k * alpha, 1.0_wp) - 0.5_wp
          case%surface_level = level
          case%history_every = case%aitken_window
          call run_sphere_array(case, result)
          call spheroid_coefficient(result, m, case, coefficient, momentum(k))
          surface(k) = norm2(result%surface_torque) / (result%drive(1) * result%radius)
          drift = 0
          last = size(result%history, 2)
          if (last >= 2) drift = abs(norm2(result%history(3:5, last)) / result%history(2, last) / &
                                     (norm2(result%history(3:5, last - 1)) / result%history(2, last - 1)) - 1)
          if (is_root()) print '(a,a,a,a,a,f5.2,a,i0,a,i0,a,i0,a,3f6.2,a,es8.1,a,es8.1,a,es8.1,a,i0,a,f7.1,a,a)', &
              '| ', trim(shapes(s)), ' | ', trim(motion_names(m)), ' | ', thin, ' | ', case%box_cells(1), 'x', &
              case%box_cells(2), 'x', case%box_cells(3), ' | ', case%offset_cells, ' | ', momentum(k), ' | ', &
              surface(k), ' | ', drift, ' | ', result%steps, ' | ', result%wall_seconds, &
              merge(' |         ', ' unsteady |', result%steady)
        end do
        if (is_root()) print '(a,a,a,a,a,i0,a,3es9.2,a,3es9.2,a)', '|   | ', trim(shapes(s)), ', ', &
            trim(motion_names(m)), ': over ', samples, ' offsets, median, rms, largest: momentum ', &
            median(momentum), sqrt(sum(momentum**2) / samples), maxval(momentum), '; face sum ', median(surface), &
            sqrt(sum(surface**2) / samples), maxval(surface), ' |'
      end do
    end do
    if (is_root()) print '(a)', ''
  end subroutine spheroid_offsets

  !> The median of a few values (for an even count the mean of the two middle values).
  real(wp) function median(values)
    real(wp), intent(in) :: values(:)
    real(wp) :: sorted(size(values))
    sorted = sorted_values(values)
    median = 0.5_wp * (sorted((size(sorted) + 1) / 2) + sorted(size(sorted) / 2 + 1))
  end function median

  !> The colon-separated fields of spec.
  subroutine split_fields(spec, fields, n)
    character(len=*), intent(in) :: spec
    character(len=*), intent(out) :: fields(:)
    integer, intent(out) :: n
    integer :: start, colon
    fields = ''
    n = 0
    start = 1
    do while (n < size(fields))
      n = n + 1
      colon = index(spec(start:), ':')
      if (colon == 0) then
        fields(n) = spec(start:)
        exit
      end if
      fields(n) = spec(start:start + colon - 2)
      start = start + colon
    end do
  end subroutine split_fields
end program bench_immersed_ladder
