!> The forcing part of the resolved scene: the Eswaran-Pope body force in the momentum
!> predictor, its state in the checkpoint, and the flow statistics (time series and spectra in
!> flow_statistics.h5, time averages in the log). Nothing is allocated when &scene forcing = 'none'.
!>
!> Per step (forced_fluid_advance): f^n from the current OU coefficients is evaluated on the faces and
!> handed to fluid_advance (added as dt f^n in the predictor), then the OU processes advance by the
!> same dt to f^{n+1}. The checkpoint stores the packed OU state and stream ('forcing/state'), so a
!> restart continues the same realisation bit for bit on any rank count.
module forcing_driver
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use deck_file, only: real_text, int_text
  use logger, only: log_line
  use error_handling, only: fatal
  use run_directory, only: run_file
  use file_system, only: file_exists, rename_file
  use parallel_env, only: is_root, barrier
  use hdf5_io, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists, h5_append, h5_write_array, h5_read_array, &
                     h5_truncate, h5_delete
  use fluid_solver, only: fluid_solver_t, fluid_advance
  use fluid_restart, only: write_fluid_state
  use checkpoint_files, only: checkpoint_t
  use eswaran_pope_forcing, only: ep_forcing_t, forcing_init_on_grid, forcing_advance, forcing_set_fields, &
                                  forcing_power_input, forcing_pack_state, forcing_unpack_state
  use flow_statistics, only: flow_statistics_t, compute_flow_statistics
  implicit none
  private
  public :: forcing_driver_t, forcing_driver_start, forced_fluid_advance, forcing_driver_statistics, &
            forcing_driver_write_checkpoint, forcing_driver_finish

  !> The time-series datasets of flow_statistics.h5 (one row per statistics output; appended in
  !> forcing_driver_statistics, which must stay in step with this list).
  character(len=*), parameter :: series_names(12) = [character(len=17) :: 'time', 'step', 'u_rms', &
      'u_rms_component', 'kinetic_energy', 'dissipation', 'power_input', 'taylor_microscale', 're_lambda', &
      'kolmogorov_length', 'kmax_eta', 'integral_length']

  type :: forcing_driver_t
    logical :: active = .false.                 !< &scene forcing = 'eswaran_pope'
    type(ep_forcing_t) :: forcing
    real(wp), allocatable :: fx(:,:,:), fy(:,:,:), fz(:,:,:)   !< m/s^2, f^n on the u, v, w faces
    type(flow_statistics_t) :: stats
    integer :: statistics_interval = 0
    real(wp) :: average_start = 0
    character(len=:), allocatable :: statistics_path
    ! Time averages over the rows with time >= average_start (this run segment).
    integer :: averaged_rows = 0
    real(wp) :: first_averaged_time = 0, last_averaged_time = 0
    real(wp) :: sum_u_rms = 0, sum_dissipation = 0, sum_power = 0, sum_re_lambda = 0, sum_eta = 0
    real(wp) :: sum_kinetic_energy = 0, sum_taylor = 0, sum_kmax_eta = 0, sum_integral = 0
  end type forcing_driver_t

contains

  !> Set up the forcing (if the deck asks) on the solver's grid; on a restart restore its state
  !> from its group of the checkpoint the fluid was read from (open when restarting). Collective.
  subroutine forcing_driver_start(driver, cfg, solver, restart)
    type(forcing_driver_t), intent(inout) :: driver
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(in) :: solver
    type(checkpoint_t), intent(in) :: restart          !< not open on a fresh start
    type(h5_file_t) :: file
    integer(i8), allocatable :: words(:)
    driver%active = (cfg%scene%forcing == 'eswaran_pope')
    if (.not. driver%active) return
    call forcing_init_on_grid(driver%forcing, cfg%forcing, cfg%run%seed, solver%grid)
    allocate(driver%fx, driver%fy, driver%fz, mold=solver%u)
    driver%fx = 0; driver%fy = 0; driver%fz = 0
    if (restart%file%is_open) then
      if (.not. h5_exists(restart%file, 'forcing/state')) call fatal('forcing: the checkpoint '//restart%path// &
          ' has no forcing state (written by a run without forcing); &scene forcing must match the run restarted')
      call h5_read_array(restart%file, 'forcing/state', words)
      call forcing_unpack_state(driver%forcing, words)
      call log_line('forcing: OU state and random stream restored from '//restart%path)
    end if
    driver%statistics_interval = cfg%forcing%statistics_interval
    driver%average_start = cfg%forcing%average_start
    driver%statistics_path = run_file('flow_statistics.h5')
    if (driver%statistics_interval > 0) then
      if (cfg%run%restart .and. file_exists(driver%statistics_path)) then
        call drop_rows_after(driver%statistics_path, solver%step)
      else
        call h5_create(file, driver%statistics_path)
        call h5_close(file)
      end if
    end if
  end subroutine forcing_driver_start

  !> A restart from the checkpoint of step last_step continues flow_statistics.h5 from there: the
  !> rows and spectra an interrupted run wrote after that step are dropped (h5_truncate, h5_delete),
  !> so every step appears once and the file equals that of an uninterrupted run. Rows are in step
  !> order; every row up to last_step is complete (the checkpoint is written after the row), while
  !> a run killed inside forcing_driver_statistics may have left some datasets one row longer.
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
      if (kept < size(steps)) call log_line('forcing: '//int_text(size(steps) - kept)//' rows after step '// &
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

  !> One fluid step with the forcing (or without, if it is off): f^n on the faces, fluid_advance,
  !> then the OU processes to the next time level. Collective.
  subroutine forced_fluid_advance(driver, solver, dt)
    type(forcing_driver_t), intent(inout) :: driver
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: dt
    if (.not. driver%active) then
      call fluid_advance(solver, dt)
      return
    end if
    call forcing_set_fields(driver%forcing, driver%fx, driver%fy, driver%fz)
    call fluid_advance(solver, dt, driver%fx, driver%fy, driver%fz)
    call forcing_advance(driver%forcing, dt)
  end subroutine forced_fluid_advance

  !> At every statistics_interval steps: the flow statistics with <f.u> (f at the current time
  !> level), one row of the time series and the spectrum in flow_statistics.h5, and a log line.
  subroutine forcing_driver_statistics(driver, solver, viscosity)
    type(forcing_driver_t), intent(inout) :: driver
    type(fluid_solver_t), intent(inout) :: solver
    real(wp), intent(in) :: viscosity
    type(h5_file_t) :: file
    real(wp) :: power
    if (.not. driver%active .or. driver%statistics_interval <= 0) return
    if (mod(solver%step, int(driver%statistics_interval, i8)) /= 0) return
    power = forcing_power_input(driver%forcing, solver%u, solver%v, solver%w)
    call compute_flow_statistics(driver%stats, solver%grid, solver%u, solver%v, solver%w, viscosity, power)
    associate (s => driver%stats)
      call h5_open(file, driver%statistics_path, writable=.true.)
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
      if (solver%time >= driver%average_start) then
        if (driver%averaged_rows == 0) driver%first_averaged_time = solver%time
        driver%last_averaged_time = solver%time
        driver%averaged_rows = driver%averaged_rows + 1
        driver%sum_u_rms = driver%sum_u_rms + s%u_rms
        driver%sum_kinetic_energy = driver%sum_kinetic_energy + s%kinetic_energy
        driver%sum_dissipation = driver%sum_dissipation + s%dissipation
        driver%sum_power = driver%sum_power + s%power_input
        driver%sum_re_lambda = driver%sum_re_lambda + s%re_lambda
        driver%sum_eta = driver%sum_eta + s%kolmogorov_length
        driver%sum_taylor = driver%sum_taylor + s%taylor_microscale
        driver%sum_kmax_eta = driver%sum_kmax_eta + s%kmax_eta
        driver%sum_integral = driver%sum_integral + s%integral_length
      end if
    end associate
  end subroutine forcing_driver_statistics

  !> The forcing's group of an open checkpoint: the packed OU state and stream (nothing when off).
  subroutine forcing_driver_write_checkpoint(driver, checkpoint)
    type(forcing_driver_t), intent(in) :: driver
    type(checkpoint_t), intent(in) :: checkpoint
    if (driver%active) call h5_write_array(checkpoint%file, 'forcing/state', forcing_pack_state(driver%forcing))
  end subroutine forcing_driver_write_checkpoint

  !> At the end of a forced run: final_field.h5 in the run directory (the velocity and pressure in
  !> the layout &fluid init = 'file' reads on any rank count: fluid/u, v, w, pressure, grid_shape,
  !> plus the time reached and the forcing state for reference), then the time averages of the flow
  !> statistics over [average_start, end] of this run segment in the log. Collective.
  subroutine forcing_driver_finish(driver, solver)
    type(forcing_driver_t), intent(inout) :: driver
    type(fluid_solver_t), intent(in) :: solver
    type(h5_file_t) :: file
    real(wp) :: rows
    if (.not. driver%active) return
    call h5_create(file, run_file('final_field.h5'), complete_on_close=.true.)
    call write_fluid_state(file, solver)
    call h5_write_array(file, 'forcing/state', forcing_pack_state(driver%forcing))
    call h5_close(file)   ! final_field.h5.tmp becomes final_field.h5 once complete
    call log_line('forcing: final field (for &fluid init = ''file'') in '//run_file('final_field.h5'))
    if (driver%averaged_rows == 0) return
    rows = real(driver%averaged_rows, wp)
    call log_line('flow averages over t = '//real_text(driver%first_averaged_time)//' .. '// &
        real_text(driver%last_averaged_time)//' s ('//int_text(driver%averaged_rows)//' rows):')
    call log_line('flow averages: u_rms = '//real_text(driver%sum_u_rms / rows)//' m/s  k = '// &
        real_text(driver%sum_kinetic_energy / rows)//' m^2/s^2  epsilon = '//real_text(driver%sum_dissipation / rows)// &
        ' m^2/s^3  <f.u> = '//real_text(driver%sum_power / rows)//' m^2/s^3')
    call log_line('flow averages: Re_lambda = '//real_text(driver%sum_re_lambda / rows)//'  lambda = '// &
        real_text(driver%sum_taylor / rows)//' m  eta = '//real_text(driver%sum_eta / rows)//' m  kmax_eta = '// &
        real_text(driver%sum_kmax_eta / rows)//'  L_int = '//real_text(driver%sum_integral / rows)//' m')
  end subroutine forcing_driver_finish
end module forcing_driver
