!> Free particles resolved by the immersed boundary (make validate; docs/studies/validation.md, "Free
!> particles"). Sections (command-line arguments; none runs all three):
!> - sphere [pressure_scheme]: a sphere settling in the periodic cube (module settling_sphere_case) at D/dx about
!>   8, 12 and 16 (phi = 0.125), its drag coefficient K = W / (6 pi mu a U_s) against Zick & Homsy
!>   (1982, J. Fluid Mech. 115, 13, Table 2: K = 4.292) and against the fixed sphere of the same cell
!>   (docs/studies/validation.md, "Immersed boundary": 4.2794, 4.2884, 4.2802); then at D/dx 8 the density
!>   ratios 2.72, 1.1, 0.5 and 0.3 (a buoyant sphere rises; at 1 there is no net weight) with and
!>   without the added-mass stabilisation. pressure_scheme (default 'incremental', the ladder's):
!>   'non_incremental', the resolved decks' default, runs the three resolutions only.
!> - spheroids [thin_cells cells_1 [cells_2 [cells_3]]]: a needle and a disk (aspect 5) settling
!>   with the axis at 45 degrees from gravity, thinnest dimension thin_cells (default 4.4) in the
!>   boxes cells_i^3 (default 32, 40, 48): the body-frame mobilities, extrapolated in the box size
!>   as in the rung-6 ladder (1/c - 2.837 r/L + C (r/L)^3 through two successive boxes), the
!>   settling speed and drift angle against Oberbeck/Perrin (module stokes_resistance), the turn.
!> - release [cells diameter_cells density_ratio viscous_number]: the quadrature of the unsteady
!>   Stokes reference (module unsteady_stokes) against its Laplace inversion and its own halved
!>   steps; then the resolved sphere released at U_0 in fluid at rest (module released_sphere_case)
!>   over tau_p against the reference: by default D/dx 8, 12 and 16 in boxes of 4 to 8 D, two
!>   smaller step, the density ratio 1, each with the stabilisation's history estimate (&scene
!>   added_mass_history) and the non-incremental pressure, and for comparison without the history
!>   estimate, without the stabilisation and with the incremental pressure (arguments after
!>   viscous_number: stabilisation, history estimate, incremental pressure, each 1 or 0; default 1 1 0).
!> Prints Markdown tables.
program bench_free_particles
  use agglo_kinds, only: wp
  use, intrinsic :: ieee_arithmetic, only: ieee_is_finite
  use physical_constants, only: pi
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use settling_sphere_case, only: settling_case_t, settling_result_t, run_settling_sphere, periodic_slip_reference, &
                                  drift_angle_degrees
  use stokes_resistance, only: spheroid_resistance_coefficients
  use unsteady_stokes, only: released_sphere_t, release_decay_quadrature, release_decay_laplace, &
                             released_start_velocity
  use released_sphere_case, only: release_case_t, release_result_t, run_released_sphere, release_comparison_t, &
                                  compare_release
  implicit none
  character(len=32) :: section
  integer :: arguments

  call parallel_start()
  arguments = command_argument_count()
  section = 'all'
  if (arguments > 0) call get_command_argument(1, section)
  select case (trim(section))
  case ('all')
    call sphere_section()
    call spheroid_section()
    call release_section()
  case ('sphere')
    call sphere_section()
  case ('spheroids')
    call spheroid_section()
  case ('release')
    call release_section()
  case default
    if (is_root()) print '(a)', 'bench_free_particles: section '''//trim(section)//''' is not sphere, spheroids or release'
    call parallel_stop()
    error stop 1
  end select
  call parallel_stop()

contains

  !> The real command-line argument position, or fallback when absent.
  real(wp) function real_argument(position, fallback) result(value)
    integer, intent(in) :: position
    real(wp), intent(in) :: fallback
    character(len=32) :: text
    integer :: status
    value = fallback
    if (command_argument_count() < position) return
    call get_command_argument(position, text)
    read(text, *, iostat=status) value
    if (status /= 0) error stop 'bench_free_particles: an argument is not a number'
  end function real_argument

  subroutine sphere_section()
    real(wp), parameter :: zick_homsy = 4.292_wp
    integer, parameter :: cells(3) = [13, 19, 26]
    real(wp), parameter :: fixed(3) = [4.2794_wp, 4.2884_wp, 4.2802_wp]
    real(wp), parameter :: ratios(4) = [2.72_wp, 1.1_wp, 0.5_wp, 0.3_wp]
    type(settling_case_t) :: case
    type(settling_result_t) :: result
    integer :: d, r, s
    logical :: stabilise
    character(len=16) :: pressure_scheme
    ! Optional second argument: the pressure scheme of the three resolutions (default the ladder's).
    pressure_scheme = 'incremental'
    if (command_argument_count() >= 2) call get_command_argument(2, pressure_scheme)
    if (is_root()) then
      print '(a)', 'pressure_scheme '//trim(pressure_scheme)
      print '(a)', '| cells | D/dx | rho_p/rho_f | stabilised | K | vs Z&H | vs fixed sphere | momentum | steps | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|'
    end if
    do d = 1, size(cells)
      case = settling_case_t(cells=cells(d), max_steps=40000, pressure_scheme=pressure_scheme)
      call run_settling_sphere(case, result)
      call print_sphere_row(case, result, fixed(d))
    end do
    if (trim(pressure_scheme) /= 'incremental') return   ! the density ratios with the ladder's scheme only
    do r = 1, size(ratios)
      do s = 1, 2   ! with, then without the stabilisation
        stabilise = s == 1
        case = settling_case_t(cells=13, density_ratio=ratios(r), stabilise=stabilise, max_steps=4000)
        call run_settling_sphere(case, result)
        call print_sphere_row(case, result, fixed(1))
      end do
    end do
  end subroutine sphere_section

  subroutine print_sphere_row(case, result, fixed_k)
    type(settling_case_t), intent(in) :: case
    type(settling_result_t), intent(in) :: result
    real(wp), intent(in) :: fixed_k
    real(wp), parameter :: zick_homsy = 4.292_wp
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
  end subroutine print_sphere_row

  !> Needle and disk at 45 degrees in two or three boxes (section header); each pair of successive
  !> boxes gives an extrapolation.
  subroutine spheroid_section()
    character(len=8), parameter :: shapes(2) = [character(len=8) :: 'needle', 'disk']
    real(wp) :: thin, ratio(3), raw(2, 3), extrapolated(2), cubic(2), c(4), unbounded(3), measured(3)
    real(wp) :: box_reference(3), speed_error, drift, drift_reference
    integer :: cells(3), boxes, s, b
    type(settling_case_t) :: case
    type(settling_result_t) :: result(3)
    thin = real_argument(2, 4.4_wp)
    cells = [32, 40, 48]
    if (command_argument_count() >= 3) cells = [nint(real_argument(3, 0.0_wp)), nint(real_argument(4, 0.0_wp)), &
                                                nint(real_argument(5, 0.0_wp))]
    boxes = count(cells > 0)
    if (is_root()) then
      print '(a,f4.1,a,3(i0,1x))', 'Spheroids settling at 45 degrees, thin dimension ', thin, ' cells, boxes ', cells(1:boxes)
      print '(a)', '| shape | box | r/L | 6 pi mu r M along / across | |U_s| / Hasimoto-only | drift angle, '// &
          'Hasimoto-only (deg) | turn (deg) | spin | momentum | steps | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|'
    end if
    do s = 1, size(shapes)
      do b = 1, boxes
        case = settling_case_t(cells=cells(b), shape=shapes(s), thin_cells=thin, tilt_degrees=45.0_wp, max_steps=40000)
        call run_settling_sphere(case, result(b))
        ratio(b) = result(b)%radius / result(b)%box
        raw(:, b) = result(b)%mobility_body(1:2)
        box_reference = periodic_slip_reference(result(b)%body_shape, result(b)%rotation, result(b)%weight, &
                                                result(b)%viscosity, result(b)%box, [0.0_wp, 0.0_wp])
        if (is_root()) print '(a,a,a,i0,a,f6.4,a,f7.4,a,f7.4,a,f6.3,a,f6.2,a,f6.2,a,es8.1,a,es8.1,a,es8.1,a,i0,a,f6.1,a)', &
            '| ', trim(shapes(s)), ' | ', cells(b), '^3 | ', ratio(b), ' | ', raw(1, b), ' / ', raw(2, b), ' | ', &
            norm2(result(b)%slip_vector) / norm2(box_reference), ' | ', &
            drift_angle_degrees(result(b)%slip_vector, result(b)%weight), ', ', &
            drift_angle_degrees(box_reference, result(b)%weight), ' | ', result(b)%turn_degrees, ' | ', result(b)%spin, &
            ' | ', result(b)%momentum, ' | ', result(b)%steps, trim(merge(' |           ', ' (unsteady) |', result(b)%steady)), &
            result(b)%wall_seconds, ' |'
      end do
      c = spheroid_resistance_coefficients(result(1)%body_shape%a, result(1)%body_shape%b)
      unbounded = periodic_slip_reference(result(1)%body_shape, result(1)%rotation, result(1)%weight, &
                                          result(1)%viscosity, huge(1.0_wp), [0.0_wp, 0.0_wp])
      drift_reference = drift_angle_degrees(unbounded, result(1)%weight)
      do b = 1, boxes - 1
        ! Per body axis: raw = 1/c - 2.837 r/L + C (r/L)^3 in the boxes b and b + 1.
        associate (r1 => ratio(b), r2 => ratio(b + 1))
          extrapolated = (raw(:, b) * r2**3 - raw(:, b + 1) * r1**3 + 2.837_wp * r1 * r2 * (r2**2 - r1**2)) / (r2**3 - r1**3)
          cubic = (raw(:, b) - extrapolated + 2.837_wp * r1) / r1**3
        end associate
        measured = matmul(result(1)%rotation, [extrapolated(1), extrapolated(2), extrapolated(2)] &
                   * matmul(result(1)%weight, result(1)%rotation)) / (6.0_wp * pi * result(1)%viscosity * result(1)%radius)
        speed_error = norm2(measured) / norm2(unbounded) - 1
        drift = drift_angle_degrees(measured, result(1)%weight)
        if (is_root()) print '(a,a,a,i0,a,i0,a,f7.4,a,f7.4,a,f6.2,a,f6.2,a,f7.1,a,f7.1,a,f6.2,a,f6.3,a,f6.3,a,f6.2,a)', &
            '| ', trim(shapes(s)), ' | ', cells(b), '^3, ', cells(b + 1), '^3 | ', 1 / extrapolated(1), ' / ', &
            1 / extrapolated(2), ' | ', 100 * (1 / (c(1) * extrapolated(1)) - 1), '% / ', &
            100 * (1 / (c(2) * extrapolated(2)) - 1), '% | ', cubic(1), ' / ', cubic(2), ' | ', 100 * speed_error, &
            '% | ', drift, ' / ', drift_reference, ' | ', 100 * (drift / drift_reference - 1), '% |'
      end do
    end do
    if (is_root()) print '(a)', 'extrapolated rows: | shape | boxes | c along / across | vs Oberbeck/Perrin | C along / '// &
        'across | |U| vs Oberbeck/Perrin | drift angle / reference (deg) | drift error |'
  end subroutine spheroid_section

  !> The reference's convergence, then the resolved releases (section header).
  subroutine release_section()
    type(released_sphere_t) :: sphere
    real(wp), allocatable :: history(:)
    real(wp) :: tau, laplace, finest
    integer :: level, steps, k, cells
    ! The reference in units where a = 1, rho_f = 1 and tau_p = 2 rho_p a^2 / (9 mu) = 1.
    sphere = released_sphere_t(radius=1.0_wp, density=2.72_wp, fluid_density=1.0_wp, viscosity=2.0_wp * 2.72_wp / 9.0_wp)
    tau = 1.0_wp
    if (is_root()) then
      print '(a)', 'Unsteady Stokes reference, density ratio 2.72: u(t) = U(t)/U(0+) at t = tau_p / 4, tau_p / 2, tau_p'
      print '(a)', '| steps per tau_p | u(tau_p/4) | u(tau_p/2) | u(tau_p) | max |u - Laplace| over [0, tau_p] |'
      print '(a)', '|---|---|---|---|---|'
    end if
    do level = 0, 4
      steps = 100 * 2**level
      allocate(history(0:steps))
      call release_decay_quadrature(sphere, tau / steps, history)
      finest = 0
      do k = 1, steps
        laplace = release_decay_laplace(sphere, k * tau / steps, 24)
        finest = max(finest, abs(history(k) - laplace))
      end do
      if (is_root()) print '(a,i0,a,f9.6,a,f9.6,a,f9.6,a,es9.2,a)', '| ', steps, ' | ', history(steps / 4), ' | ', &
          history(steps / 2), ' | ', history(steps), ' | ', finest, ' |'
      deallocate(history)
    end do
    if (is_root()) print '(a,f9.6,a,f9.6)', 'Laplace (Talbot) u(tau_p), 16 / 32 nodes: ', &
        release_decay_laplace(sphere, tau, 16), ' / ', release_decay_laplace(sphere, tau, 32)
    if (is_root()) then
      print '(a)', 'Resolved release against the reference (U_p / U_0; late: t >= 0.05 tau_p; displacement over [0, tau_p])'
      print '(a)', '| box | D/dx | rho_p/rho_f | stabilisation | pressure | nu dt/dx^2 | steps | U_p/U_0 steps 1-3 | '// &
          'max diff | max rel. late | displacement | rel. at tau_p | momentum | wall s |'
      print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|'
    end if
    cells = nint(real_argument(2, 0.0_wp))
    if (cells > 0) then
      call release_row(release_case_t(cells=cells, diameter_cells=real_argument(3, 8.0_wp), &
                                      density_ratio=real_argument(4, 2.72_wp), viscous_number=real_argument(5, 0.06_wp), &
                                      stabilise=real_argument(6, 1.0_wp) > 0.5_wp, &
                                      history=real_argument(7, 1.0_wp) > 0.5_wp, &
                                      pressure_scheme=merge('incremental    ', 'non_incremental', &
                                                            real_argument(8, 0.0_wp) > 0.5_wp)))
      return
    end if
    ! The box (4, 6, 8 D at D/dx 8; 4, 6 D at 12; 4 D at 16), the step, the density ratio; then
    ! what each part of the coupling does (the history estimate, the stabilisation, the pressure).
    call release_row(release_case_t(cells=32, diameter_cells=8.0_wp))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp))
    call release_row(release_case_t(cells=64, diameter_cells=8.0_wp))
    call release_row(release_case_t(cells=48, diameter_cells=12.0_wp))
    call release_row(release_case_t(cells=72, diameter_cells=12.0_wp))
    call release_row(release_case_t(cells=64, diameter_cells=16.0_wp))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, viscous_number=0.015_wp))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, density_ratio=1.0_wp))
    call release_row(release_case_t(cells=72, diameter_cells=12.0_wp, density_ratio=1.0_wp))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, density_ratio=1.0_wp, viscous_number=0.015_wp))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, history=.false.))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, stabilise=.false.))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, pressure_scheme='incremental'))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, history=.false., pressure_scheme='incremental'))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, density_ratio=1.0_wp, history=.false.))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, density_ratio=1.0_wp, stabilise=.false.))
    call release_row(release_case_t(cells=48, diameter_cells=8.0_wp, density_ratio=1.0_wp, history=.false., &
                                    pressure_scheme='incremental'))
  end subroutine release_section

  !> One resolved release against the reference on the run's own steps (refined 16 times): the
  !> largest difference of U_p / U_0 over the run, the largest relative one after the first 5% of
  !> tau_p, and the distance travelled (trapezoid rule on the steps).
  subroutine release_row(case)
    type(release_case_t), intent(in) :: case
    integer, parameter :: refine = 16
    type(release_result_t) :: result
    type(release_comparison_t) :: comparison
    call run_released_sphere(case, result)
    call compare_release(result, refine, 0.05_wp, comparison)
    if (is_root()) print '(a,3f8.4)', '  reference after steps 1-3:', comparison%first_reference
    if (is_root()) print '(a,i0,a,f5.2,a,f4.2,a,a,a,a,a,f6.4,a,i0,a,3(f7.4,a),f7.4,a,f7.4,a,f8.4,a,f8.4,a,f8.5,a,f7.1,a)', &
        '| ', case%cells, '^3 | ', case%diameter_cells, ' | ', case%density_ratio, ' | ', &
        trim(merge(merge('M_a + history', 'M_a          ', case%history), 'off          ', case%stabilise)), ' | ', &
        trim(case%pressure_scheme), ' | ', case%viscous_number, ' | ', &
        comparison%steps, ' | ', comparison%first(1), ', ', comparison%first(2), ', ', comparison%first(3), ' | ', &
        comparison%largest_difference, ' | ', comparison%largest_relative_late, ' | ', comparison%displacement_error, &
        ' | ', comparison%final_relative, ' | ', result%momentum, ' | ', result%wall_seconds, ' |'
  end subroutine release_row
end program bench_free_particles
