!> Namelist group &run: run identity, random seed, restart, time span and time step.
module config_run
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_positive_int, &
                       require_option, require_range, real_text
  use error_handling, only: input_error
  implicit none
  private
  public :: run_config_t, read_run_group, check_run_group, write_run_group

  type :: run_config_t
    character(len=256) :: name = 'agglo'         !< run name, written into every output (NAME_MAX 255)
    integer :: seed = 20250224                   !< seed of every random stream of the run
    logical :: restart = .false.                 !< continue from the newest complete checkpoint
    logical :: overwrite = .false.               !< allow replacing the outputs of an earlier run
    real(wp) :: end_time = 1.0e-3_wp             !< s, simulated time at which the run stops
    integer :: max_steps = 1000000000            !< the run also stops after this many steps
    real(wp) :: dt = 1.0e-5_wp                   !< s, time step (fixed) or first/maximum step (cfl)
    character(len=16) :: dt_mode = 'fixed'       !< 'fixed' | 'cfl'
    real(wp) :: cfl_target = 0.5_wp              !< CFL number aimed at when dt_mode = 'cfl'
    real(wp) :: cfl_limit = 1.0_wp               !< the run stops if the CFL number exceeds this
    integer :: progress_interval = 10            !< steps between progress lines
  end type run_config_t

  ! The namelist objects: module variables named as in the deck, copied to/from the type.
  character(len=256) :: name
  integer :: seed, max_steps, progress_interval
  logical :: restart, overwrite
  real(wp) :: end_time, dt, cfl_target, cfl_limit
  character(len=16) :: dt_mode
  namelist /run/ name, seed, restart, overwrite, end_time, max_steps, dt, dt_mode, cfl_target, &
                 cfl_limit, progress_interval

contains

  subroutine to_namelist(cfg)
    type(run_config_t), intent(in) :: cfg
    name = cfg%name; seed = cfg%seed; restart = cfg%restart; overwrite = cfg%overwrite
    end_time = cfg%end_time; max_steps = cfg%max_steps; dt = cfg%dt; dt_mode = cfg%dt_mode
    cfl_target = cfg%cfl_target; cfl_limit = cfg%cfl_limit; progress_interval = cfg%progress_interval
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(run_config_t), intent(inout) :: cfg
    cfg%name = name; cfg%seed = seed; cfg%restart = restart; cfg%overwrite = overwrite
    cfg%end_time = end_time; cfg%max_steps = max_steps; cfg%dt = dt; cfg%dt_mode = dt_mode
    cfg%cfl_target = cfl_target; cfg%cfl_limit = cfl_limit; cfg%progress_interval = progress_interval
  end subroutine from_namelist

  !> Defaults, then whatever the deck's &run sets.
  subroutine read_run_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(run_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=run, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'run', ios, message)
    call from_namelist(cfg)
  end subroutine read_run_group

  subroutine check_run_group(cfg)
    type(run_config_t), intent(in) :: cfg
    if (len_trim(cfg%name) == 0 .or. scan(trim(cfg%name), ' /\"''') > 0) call input_error('run', 'name', &
        ''''//trim(cfg%name)//'''', 'a non-empty name without spaces, quotes or "/"')
    call require_positive('run', 'end_time', cfg%end_time)
    call require_positive_int('run', 'max_steps', cfg%max_steps)
    call require_positive('run', 'dt', cfg%dt)
    call require_option('run', 'dt_mode', cfg%dt_mode, [character(len=8) :: 'fixed', 'cfl'])
    call require_range('run', 'cfl_target', cfg%cfl_target, 1.0e-3_wp, 1.0_wp)
    call require_range('run', 'cfl_limit', cfg%cfl_limit, 1.0e-3_wp, 2.0_wp)
    if (cfg%cfl_target > cfg%cfl_limit) call input_error('run', 'cfl_target', real_text(cfg%cfl_target), &
        '<= cfl_limit = '//real_text(cfg%cfl_limit))
    call require_positive_int('run', 'progress_interval', cfg%progress_interval)
  end subroutine check_run_group

  !> The resolved group, as a namelist (for the log and the run directory).
  subroutine write_run_group(unit, cfg)
    integer, intent(in) :: unit
    type(run_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=run)
  end subroutine write_run_group
end module config_run
