!> Moving bodies (make validate; docs/studies/validation.md, "Moving bodies: status changes and the
!> oscillating sphere"): the oscillating sphere (validation ladder rung 8) against Stokes' (1851)
!> force with the periodic box's mean-flow correction (validation/oscillating_sphere_case.f90), at
!> D/dx = 8 and 12 in boxes L = 8 R and (D/dx = 8) L = 12 R, with the incremental pressure, the
!> incremental pressure without the sealed cells' extrapolation (the scheme before it, for the
!> spikes), and the pressure-free projection. Prints a Markdown table: force amplitude and phase
!> errors, the errors of the in-phase (with the velocity: drag) and out-of-phase (with the
!> acceleration: added mass and history) parts, the largest spike (second difference / 2) and the
!> largest residual of the fit over the force amplitude, the logged load jump at status changes
!> and at other steps (over the rms load).
program bench_immersed_moving
  use agglo_kinds, only: wp
  use physical_constants, only: pi
  use parallel_env, only: parallel_start, parallel_stop, is_root
  use oscillating_sphere_case, only: oscillating_sphere_case_t, oscillating_sphere_result_t, run_oscillating_sphere
  implicit none
  integer, parameter :: n_runs = 6
  integer, parameter :: cells(n_runs) = [32, 32, 32, 48, 48, 48]
  real(wp), parameter :: diameters(n_runs) = [8.0_wp, 8.0_wp, 8.0_wp, 12.0_wp, 12.0_wp, 8.0_wp]
  character(len=16), parameter :: schemes(n_runs) = [character(len=16) :: 'incremental', 'incremental', &
      'non_incremental', 'incremental', 'incremental', 'incremental']
  logical, parameter :: extended(n_runs) = [.true., .false., .true., .true., .false., .true.]
  type(oscillating_sphere_case_t) :: case
  type(oscillating_sphere_result_t) :: result
  integer :: r
  character(len=*), parameter :: row_format = &
      '(a,i0,a,f4.1,a,f4.1,a,a,a,a,a,i0,a,f5.3,a,f6.2,a,f6.2,2(a,f6.2),a,f6.2,a,f6.2,a,f6.3,a,f6.3,a,i0,a,f6.1,a)'

  call parallel_start()
  if (is_root()) then
    print '(a)', '| cells | D/dx | L/R | pressure | sealed cells | steps/period | A/R | amplitude error | phase error | ' // &
        'in-phase part | out-of-phase part | spike / amplitude | fit residual / amplitude | ' // &
        'jump at changes / rms | jump otherwise / rms | uncovered | wall s |'
    print '(a)', '|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|'
  end if
  do r = 1, n_runs
    case%cells = cells(r)
    case%diameter_cells = diameters(r)
    case%pressure_scheme = schemes(r)
    case%extend_pressure = extended(r)
    call run_oscillating_sphere(case, result)
    if (is_root()) print row_format, &
        '| ', case%cells, '^3 | ', case%diameter_cells, ' | ', 2 * case%cells / case%diameter_cells, ' | ', &
        trim(case%pressure_scheme), ' | ', trim(merge('extrapolated', 'as projected', case%extend_pressure)), ' | ', &
        result%steps_per_period, ' | ', result%amplitude_over_radius, ' | ', 100 * result%amplitude_error, '% | ', &
        result%phase_error * 180 / pi, ' deg | ', 100 * (real(result%force) / real(result%reference) - 1), '% | ', &
        100 * (aimag(result%force) / aimag(result%reference) - 1), '% | ', 100 * result%largest_spike, '% | ', &
        100 * result%largest_residual, '% | ', result%jump_at_changes, ' | ', result%jump_otherwise, ' | ', &
        result%uncovered, ' | ', result%wall_seconds, ' |'
  end do
  call parallel_stop()
end program bench_immersed_moving
