!> The forcing part of the resolved scene: the Eswaran-Pope body force in the momentum
!> predictor, its state in the checkpoint, its power input <f.u> for the flow statistics
!> (flow_statistics_output) and the final field. Nothing is allocated when &scene forcing = 'none'.
!>
!> Per step (forced_fluid_advance): f^n from the current OU coefficients is evaluated on the faces and
!> handed to fluid_advance (added as dt f^n in the predictor), then the OU processes advance by the
!> same dt to f^{n+1}. The checkpoint stores the packed OU state and stream ('forcing/state'), so a
!> restart continues the same realisation bit for bit on any rank count.
!> A fresh start from a forced field (&fluid init = 'file') takes the OU coefficients stored with it
!> (&forcing initial_state = 'field', default) and the deck's own stream: forcing and field start
!> correlated, so the box stays stationary (docs/theory.md, "Forcing").
module forcing_driver
  use agglo_kinds, only: wp, i8
  use agglo_config, only: agglo_config_t
  use logger, only: log_line
  use error_handling, only: fatal
  use run_directory, only: run_file
  use timer_registry, only: timer_tic, timer_toc
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists
  use hdf5_datasets, only: h5_write_array, h5_read_array
  use fluid_solver, only: fluid_solver_t, fluid_advance
  use fluid_restart, only: write_fluid_state
  use checkpoint_files, only: checkpoint_t
  use eswaran_pope_forcing, only: ep_forcing_t, forcing_init_on_grid, forcing_advance, forcing_set_fields, &
                                  forcing_power_input, forcing_pack_state, forcing_unpack_state, &
                                  forcing_restore_coefficients
  implicit none
  private
  public :: forcing_driver_t, forcing_driver_start, forced_fluid_advance, forcing_driver_power_input, &
            forcing_driver_write_checkpoint, forcing_driver_finish, forcing_driver_evaluate, forcing_driver_advance

  type :: forcing_driver_t
    logical :: active = .false.                 !< &scene forcing = 'eswaran_pope'
    type(ep_forcing_t) :: forcing
    real(wp), allocatable :: fx(:,:,:), fy(:,:,:), fz(:,:,:)   !< m/s^2, f^n on the u, v, w faces
  end type forcing_driver_t

contains

  !> Set up the forcing (if the deck asks) on the solver's grid; on a restart restore its state
  !> from its group of the checkpoint the fluid was read from (open when restarting). On a fresh
  !> start from a field file (&fluid init = 'file') with &forcing initial_state = 'field', take the
  !> OU coefficients stored with that field (start_from_field_state). Collective.
  subroutine forcing_driver_start(driver, cfg, solver, restart)
    type(forcing_driver_t), intent(inout) :: driver
    type(agglo_config_t), intent(in) :: cfg
    type(fluid_solver_t), intent(in) :: solver
    type(checkpoint_t), intent(in) :: restart          !< not open on a fresh start
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
    else if (trim(cfg%fluid%init) == 'file' .and. trim(cfg%forcing%initial_state) == 'field') then
      call start_from_field_state(driver, trim(cfg%fluid%init_file))
    else
      call log_line('forcing: OU coefficients drawn from the stationary distribution N(0, sigma^2)')
    end if
  end subroutine forcing_driver_start

  !> The OU coefficients b^ of the forced run that wrote the initial field (its forcing/state: a
  !> final_field.h5 or a checkpoint), so that f starts correlated with u and the power input <f.u>
  !> at its stationary value; coefficients drawn afresh are uncorrelated with u, <f.u> starts near
  !> zero and the box loses energy for several k/epsilon (docs/theory.md). The deck's stream is kept.
  subroutine start_from_field_state(driver, path)
    type(forcing_driver_t), intent(inout) :: driver
    character(len=*), intent(in) :: path
    type(h5_file_t) :: file
    integer(i8), allocatable :: words(:)
    call h5_open(file, path, writable=.false.)
    if (.not. h5_exists(file, 'forcing/state')) call fatal('forcing: &forcing initial_state = ''field'' '// &
        'with &fluid init = ''file'' needs the forcing state (forcing/state) of the run that wrote '// &
        '&fluid init_file = '''//path//''', which has none (a field snapshot or a run without forcing); '// &
        'give the final_field.h5 or a checkpoint of a forced run, or set &forcing initial_state = ''stationary''')
    call h5_read_array(file, 'forcing/state', words)
    call h5_close(file)
    call forcing_restore_coefficients(driver%forcing, words, '&fluid init_file '''//path//'''')
    call log_line('forcing: OU coefficients from the initial field '//path//' (&forcing initial_state = '// &
        '''field''); random stream from &run seed')
  end subroutine start_from_field_state

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
    call forcing_driver_evaluate(driver)
    call fluid_advance(solver, dt, driver%fx, driver%fy, driver%fz)
    call forcing_driver_advance(driver, dt)
  end subroutine forced_fluid_advance

  !> f^n from the current OU coefficients on the faces (fx, fy, fz), for a step that takes it as
  !> its body force (forced_fluid_advance, or the staged step with immersed bodies). Active only.
  subroutine forcing_driver_evaluate(driver)
    type(forcing_driver_t), intent(inout) :: driver
    call timer_tic('forcing')
    call forcing_set_fields(driver%forcing, driver%fx, driver%fy, driver%fz)
    call timer_toc('forcing')
  end subroutine forcing_driver_evaluate

  !> The OU processes from the time level of the step just taken to the next (after the step that
  !> used f^n). Active only.
  subroutine forcing_driver_advance(driver, dt)
    type(forcing_driver_t), intent(inout) :: driver
    real(wp), intent(in) :: dt
    call timer_tic('forcing')
    call forcing_advance(driver%forcing, dt)
    call timer_toc('forcing')
  end subroutine forcing_driver_advance

  !> <f.u> (m^2/s^3) of the current velocity with f at the current time level; 0 when the forcing
  !> is off. Collective.
  function forcing_driver_power_input(driver, solver) result(power)
    type(forcing_driver_t), intent(in) :: driver
    type(fluid_solver_t), intent(in) :: solver
    real(wp) :: power
    power = 0.0_wp
    if (driver%active) power = forcing_power_input(driver%forcing, solver%u, solver%v, solver%w)
  end function forcing_driver_power_input

  !> The forcing's group of an open checkpoint: the packed OU state and stream (nothing when off).
  subroutine forcing_driver_write_checkpoint(driver, checkpoint)
    type(forcing_driver_t), intent(in) :: driver
    type(checkpoint_t), intent(in) :: checkpoint
    if (driver%active) call h5_write_array(checkpoint%file, 'forcing/state', forcing_pack_state(driver%forcing))
  end subroutine forcing_driver_write_checkpoint

  !> At the end of a forced run: final_field.h5 in the run directory (the velocity and pressure in
  !> the layout &fluid init = 'file' reads on any rank count: fluid/u, v, w, pressure, grid_shape,
  !> plus the forcing state, whose OU coefficients a run started from this field takes with
  !> &forcing initial_state = 'field'). Collective.
  subroutine forcing_driver_finish(driver, solver)
    type(forcing_driver_t), intent(inout) :: driver
    type(fluid_solver_t), intent(in) :: solver
    type(h5_file_t) :: file
    if (.not. driver%active) return
    call h5_create(file, run_file('final_field.h5'), complete_on_close=.true.)
    call write_fluid_state(file, solver)
    call h5_write_array(file, 'forcing/state', forcing_pack_state(driver%forcing))
    call h5_close(file)   ! final_field.h5.tmp becomes final_field.h5 once complete
    call log_line('forcing: final field (for &fluid init = ''file'') in '//run_file('final_field.h5'))
  end subroutine forcing_driver_finish
end module forcing_driver
