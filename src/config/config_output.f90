!> Namelist group &output: where results go and how often each kind is written.
module config_output
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_nonnegative, require_positive_int, int_text
  use error_handling, only: input_error
  use file_system, only: longest_path
  implicit none
  private
  public :: output_config_t, read_output_group, check_output_group, write_output_group

  type :: output_config_t
    character(len=longest_path + 1) :: directory = ''   !< run directory; '' means output/<run name>
    integer :: stats_interval = 1             !< steps between time-series rows (fluid and particles)
    !> particle steps between particles.h5 rows; 0 = stats_interval
    integer :: particle_interval = 0
    real(wp) :: field_interval = 0.0_wp       !< s of simulated time between field snapshots; 0 = start and end only
    integer :: checkpoint_interval = 0        !< steps between checkpoints; 0 = only at the end
    integer :: checkpoints_kept = 2           !< older complete checkpoints are deleted beyond this
    integer :: flow_statistics_interval = 0   !< steps between flow-statistics rows in any resolved run;
                                              !< 0 = &forcing statistics_interval if forced, else none
  end type output_config_t

  character(len=longest_path + 1) :: directory
  integer :: stats_interval, checkpoint_interval, checkpoints_kept, flow_statistics_interval, particle_interval
  real(wp) :: field_interval
  namelist /output/ directory, stats_interval, field_interval, checkpoint_interval, checkpoints_kept, &
                    flow_statistics_interval, particle_interval

contains

  subroutine to_namelist(cfg)
    type(output_config_t), intent(in) :: cfg
    directory = cfg%directory; stats_interval = cfg%stats_interval; field_interval = cfg%field_interval
    checkpoint_interval = cfg%checkpoint_interval; checkpoints_kept = cfg%checkpoints_kept
    flow_statistics_interval = cfg%flow_statistics_interval; particle_interval = cfg%particle_interval
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(output_config_t), intent(inout) :: cfg
    cfg%directory = directory; cfg%stats_interval = stats_interval; cfg%field_interval = field_interval
    cfg%checkpoint_interval = checkpoint_interval; cfg%checkpoints_kept = checkpoints_kept
    cfg%flow_statistics_interval = flow_statistics_interval; cfg%particle_interval = particle_interval
  end subroutine from_namelist

  subroutine read_output_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(output_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=output, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'output', ios, message)
    call from_namelist(cfg)
  end subroutine read_output_group

  subroutine check_output_group(cfg)
    type(output_config_t), intent(in) :: cfg
    call require_positive_int('output', 'stats_interval', cfg%stats_interval)
    call require_nonnegative('output', 'field_interval', cfg%field_interval)
    if (cfg%checkpoint_interval /= 0) call require_positive_int('output', 'checkpoint_interval', cfg%checkpoint_interval)
    call require_positive_int('output', 'checkpoints_kept', cfg%checkpoints_kept)
    if (cfg%particle_interval < 0) call input_error('output', 'particle_interval', int_text(cfg%particle_interval), &
        '>= 0 (particle steps between particles.h5 rows; 0 = stats_interval)')
    if (cfg%flow_statistics_interval < 0) call input_error('output', 'flow_statistics_interval', &
        int_text(cfg%flow_statistics_interval), '>= 0 (steps between flow-statistics rows; 0 = as &forcing says)')
  end subroutine check_output_group

  subroutine write_output_group(unit, cfg)
    integer, intent(in) :: unit
    type(output_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=output)
  end subroutine write_output_group
end module config_output
