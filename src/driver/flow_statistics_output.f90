!> Flow statistics of a resolved run (any resolved run, forced or not): every interval steps the
!> statistics of flow_statistics (u_rms, k, epsilon, <f.u>, lambda, Re_lambda, eta, kappa_max eta,
!> L_int, the spectrum E(k)) as one row of the time series and one spectrum in flow_statistics.h5
!> and a "flow:" line in the log; at the end their time averages over t >= average_start.
!> The interval: &output flow_statistics_interval if > 0, else &forcing statistics_interval in a
!> forced run, else none (nothing is computed or written). <f.u> comes from the caller (0 without
!> forcing); the averages start at &forcing average_start in a forced run and at 0 otherwise.
module flow_statistics_output
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use text_format, only: real_text, int_text
  use logger, only: log_line
  use run_directory, only: run_file
  use timer_registry, only: timer_tic, timer_toc
  use file_system, only: file_exists
  use parallel_env, only: any_rank
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists, h5_delete
  use hdf5_datasets, only: h5_write_array, h5_read_array
  use hdf5_series, only: h5_append, h5_truncate
  use fluid_solver, only: fluid_solver_t
  use flow_statistics, only: flow_statistics_t, compute_flow_statistics
  implicit none
  private
  public :: flow_output_t, flow_output_start, flow_output_due, flow_output_record, flow_output_finish

  !> The time-series datasets of flow_statistics.h5 (one row per statistics output; appended in
  !> flow_output_record, which must stay in step with this list).
  character(len=*), parameter :: series_names(12) = [character(len=17) :: 'time', 'step', 'u_rms', &
      'u_rms_component', 'kinetic_energy', 'dissipation', 'power_input', 'taylor_microscale', 're_lambda', &
      'kolmogorov_length', 'kmax_eta', 'integral_length']

  type :: flow_output_t
    integer :: interval = 0                     !< steps between rows; 0 = none
    real(wp) :: average_start = 0               !< s
    type(flow_statistics_t) :: stats
    character(len=:), allocatable :: path
    ! Time averages over the rows with time >= average_start (this run segment).
    integer :: averaged_rows = 0
    real(wp) :: first_averaged_time = 0, last_averaged_time = 0
    real(wp) :: sum_u_rms = 0, sum_dissipation = 0, sum_power = 0, sum_re_lambda = 0, sum_eta = 0
    real(wp) :: sum_kinetic_energy = 0, sum_taylor = 0, sum_kmax_eta = 0, sum_integral = 0
  end type flow_output_t

contains

  !> The interval from the deck; flow_statistics.h5 created, or on a restart continued from the
  !> step of the checkpoint (solver%step). Collective.
  subroutine flow_output_start(output, cfg, solver)
    type(flow_output_t), intent(inout) :: output
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(in) :: solver
    type(h5_file_t) :: file
    logical :: forced
    forced = (cfg%scene%forcing == 'eswaran_pope')
    output%interval = 0
    if (forced) output%interval = cfg%forcing%statistics_interval
    if (cfg%output%flow_statistics_interval > 0) output%interval = cfg%output%flow_statistics_interval
    output%average_start = 0
    if (forced) output%average_start = cfg%forcing%average_start
    if (output%interval <= 0) return
    output%path = run_file('flow_statistics.h5')
    ! One answer for all ranks (each looks for itself): they must all open, or all create, the file.
    if (cfg%run%restart .and. any_rank(file_exists(output%path))) then
      call drop_rows_after(output%path, solver%step)
    else
      call h5_create(file, output%path)
      call h5_close(file)
    end if
  end subroutine flow_output_start

  !> A restart from the checkpoint of step last_step continues flow_statistics.h5 from there: the
  !> rows and spectra an interrupted run wrote after that step are dropped (h5_truncate, h5_delete),
  !> so every step appears once and the file equals that of an uninterrupted run. Rows are in step
  !> order; every row up to last_step is complete (the checkpoint is written after the row), while
  !> a run killed inside flow_output_record may have left some datasets one row longer.
  !> Collective.
  subroutine drop_rows_after(path, last_step)
    character(len=*), intent(in) :: path
    integer(i8), intent(in) :: last_step
    type(h5_file_t) :: file
    integer, allocatable :: steps(:)
    integer :: kept, row, n
    call h5_open(file, path, writable=.true.)
    if (h5_exists(file, 'step')) then
      call h5_read_array(file, 'step', steps)
      kept = count(steps <= last_step)
      do row = kept + 1, size(steps)
        call h5_delete(file, spectrum_name(int(steps(row), i8)))
      end do
      do n = 1, size(series_names)
        if (h5_exists(file, trim(series_names(n)))) call h5_truncate(file, trim(series_names(n)), kept)
      end do
      if (kept < size(steps)) call log_line('flow statistics: '//int_text(size(steps) - kept)//' rows after step '// &
          int_text(int(last_step))//' (written after the checkpoint) dropped from '//path)
    end if
    call h5_close(file)
  end subroutine drop_rows_after

  !> spectra/energy_<step, 10 digits>
  function spectrum_name(step) result(name)
    integer(i8), intent(in) :: step
    character(len=:), allocatable :: name
    character(len=10) :: step_text
    write(step_text, '(i10.10)') step
    name = 'spectra/energy_'//step_text
  end function spectrum_name

  !> Whether the step just taken gets a row (the caller then evaluates <f.u> and records).
  logical function flow_output_due(output, step)
    type(flow_output_t), intent(in) :: output
    integer(i8), intent(in) :: step
    flow_output_due = .false.
    if (output%interval > 0) flow_output_due = (mod(step, int(output%interval, i8)) == 0)
  end function flow_output_due

  !> The flow statistics of the current field with <f.u> = power_input (f at the current time
  !> level; 0 without forcing), one row of the time series and the spectrum in flow_statistics.h5,
  !> and a log line. Collective.
  subroutine flow_output_record(output, solver, power_input)
    type(flow_output_t), intent(inout) :: output
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: power_input
    type(h5_file_t) :: file
    call timer_tic('flow statistics')
    call compute_flow_statistics(output%stats, solver, power_input)
    call timer_toc('flow statistics')
    associate (s => output%stats)
      call h5_open(file, output%path, writable=.true.)
      call h5_append(file, 'time', [solver%time])
      call h5_append(file, 'step', [int(solver%step)])
      call h5_append(file, 'u_rms', [s%u_rms])
      call h5_append(file, 'u_rms_component', reshape(s%u_rms_component, [3, 1]))
      call h5_append(file, 'kinetic_energy', [s%kinetic_energy])
      call h5_append(file, 'dissipation', [s%dissipation])
      call h5_append(file, 'power_input', [s%power_input])
      call h5_append(file, 'taylor_microscale', [s%taylor_microscale])
      call h5_append(file, 're_lambda', [s%re_lambda])
      call h5_append(file, 'kolmogorov_length', [s%kolmogorov_length])
      call h5_append(file, 'kmax_eta', [s%kmax_eta])
      call h5_append(file, 'integral_length', [s%integral_length])
      if (.not. h5_exists(file, 'spectra/wavenumber')) call h5_write_array(file, 'spectra/wavenumber', s%wavenumber)
      call h5_write_array(file, spectrum_name(solver%step), s%spectrum)
      call h5_close(file)
      call log_line('flow: t = '//real_text(solver%time)//' s  u_rms = '//real_text(s%u_rms)//' m/s  epsilon = '// &
          real_text(s%dissipation)//'  <f.u> = '//real_text(s%power_input)//' m^2/s^3  Re_lambda = '// &
          real_text(s%re_lambda)//'  eta = '//real_text(s%kolmogorov_length)//' m  kmax_eta = '//real_text(s%kmax_eta))
      if (solver%time >= output%average_start) then
        if (output%averaged_rows == 0) output%first_averaged_time = solver%time
        output%last_averaged_time = solver%time
        output%averaged_rows = output%averaged_rows + 1
        output%sum_u_rms = output%sum_u_rms + s%u_rms
        output%sum_kinetic_energy = output%sum_kinetic_energy + s%kinetic_energy
        output%sum_dissipation = output%sum_dissipation + s%dissipation
        output%sum_power = output%sum_power + s%power_input
        output%sum_re_lambda = output%sum_re_lambda + s%re_lambda
        output%sum_eta = output%sum_eta + s%kolmogorov_length
        output%sum_taylor = output%sum_taylor + s%taylor_microscale
        output%sum_kmax_eta = output%sum_kmax_eta + s%kmax_eta
        output%sum_integral = output%sum_integral + s%integral_length
      end if
    end associate
  end subroutine flow_output_record

  !> The time averages over [average_start, end] of this run segment, in the log.
  subroutine flow_output_finish(output)
    type(flow_output_t), intent(in) :: output
    real(wp) :: rows
    if (output%averaged_rows == 0) return
    rows = real(output%averaged_rows, wp)
    call log_line('flow averages over t = '//real_text(output%first_averaged_time)//' .. '// &
        real_text(output%last_averaged_time)//' s ('//int_text(output%averaged_rows)//' rows):')
    call log_line('flow averages: u_rms = '//real_text(output%sum_u_rms / rows)//' m/s  k = '// &
        real_text(output%sum_kinetic_energy / rows)//' m^2/s^2  epsilon = '//real_text(output%sum_dissipation / rows)// &
        ' m^2/s^3  <f.u> = '//real_text(output%sum_power / rows)//' m^2/s^3')
    call log_line('flow averages: Re_lambda = '//real_text(output%sum_re_lambda / rows)//'  lambda = '// &
        real_text(output%sum_taylor / rows)//' m  eta = '//real_text(output%sum_eta / rows)//' m  kmax_eta = '// &
        real_text(output%sum_kmax_eta / rows)//'  L_int = '//real_text(output%sum_integral / rows)//' m')
  end subroutine flow_output_finish
end module flow_statistics_output
