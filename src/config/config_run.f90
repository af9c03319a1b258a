!> Namelist group &run: run identity, random seed, restart, time span and time step.
module config_run
  use agglo_kinds, only: wp, i8
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_positive_int, &
                       require_option, require_range, real_text, int_text
  use error_handling, only: input_error
  implicit none
  private
  public :: run_config_t, read_run_group, check_run_group, write_run_group, step_count_limit

  !> Steps a run may need to reach end_time with the default max_steps: beyond it a run cannot end in
  !> any useful wall time (1e9 steps at 0.1 ms each are 28 hours on the smallest grid), so such a
  !> deck is an error (a dt or end_time typed wrong), not a run to start.
  real(wp), parameter :: largest_step_count = 1.0e9_wp

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
    call check_step_count(cfg)
  end subroutine check_run_group

  !> The most steps a run may need to reach end_time: max_steps, or 1e9 if that is more. A run
  !> stopped by a smaller max_steps on purpose is a run of that many steps and may have a later
  !> end_time (a restart continues it), but not one a billion steps away.
  pure real(wp) function step_count_limit(cfg)
    type(run_config_t), intent(in) :: cfg
    step_count_limit = max(real(cfg%max_steps, wp), largest_step_count)
  end function step_count_limit

  !> end_time / dt, the fewest steps to end_time (with dt_mode = 'cfl' dt is the largest step, so
  !> the run takes at least that many), must be within step_count_limit: a dt of 1e-300 s would
  !> otherwise run until max_steps without getting anywhere. The relative slack of 1e-9 lets
  !> end_time = 1, dt = 1e-9 (10^9 steps up to round-off) through.
  subroutine check_step_count(cfg)
    type(run_config_t), intent(in) :: cfg
    real(wp) :: steps
    character(len=:), allocatable :: fewest
    steps = cfg%end_time / cfg%dt
    if (.not. (steps > step_count_limit(cfg) * (1.0_wp + 1.0e-9_wp))) return
    fewest = 'end_time / dt = '//real_text(steps)//' steps'
    if (cfg%dt_mode == 'cfl') fewest = fewest//' at least (with dt_mode = ''cfl'' dt is the largest step)'
    call input_error('run', 'dt', real_text(cfg%dt), 'a step that reaches end_time = '//real_text(cfg%end_time)// &
        ' s within '//int_text(int(step_count_limit(cfg), i8))//' steps, max(max_steps, 1e9); '//fewest// &
        ' (raise dt or lower end_time)')
  end subroutine check_step_count

  !> The resolved group, as a namelist (for the log and the run directory).
  subroutine write_run_group(unit, cfg)
    integer, intent(in) :: unit
    type(run_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=run)
  end subroutine write_run_group
end module config_run
