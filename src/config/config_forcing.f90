!> Namelist group &forcing: Eswaran-Pope stochastic forcing (stub: extended by the forcing work).
module config_forcing
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive
  implicit none
  private
  public :: forcing_config_t, read_forcing_group, check_forcing_group, write_forcing_group

  type :: forcing_config_t
    real(wp) :: time_scale = 0.01_wp   !< s, Lagrangian time scale T_L of the Ornstein-Uhlenbeck processes
  end type forcing_config_t

  real(wp) :: time_scale
  namelist /forcing/ time_scale

contains

  subroutine to_namelist(cfg)
    type(forcing_config_t), intent(in) :: cfg
    time_scale = cfg%time_scale
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(forcing_config_t), intent(inout) :: cfg
    cfg%time_scale = time_scale
  end subroutine from_namelist

  subroutine read_forcing_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(forcing_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=forcing, iostat=ios, iomsg=message)
    call check_namelist_read('forcing', ios, message)
    call from_namelist(cfg)
  end subroutine read_forcing_group

  subroutine check_forcing_group(cfg)
    type(forcing_config_t), intent(in) :: cfg
    call require_positive('forcing', 'time_scale', cfg%time_scale)
  end subroutine check_forcing_group

  subroutine write_forcing_group(unit, cfg)
    integer, intent(in) :: unit
    type(forcing_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=forcing)
  end subroutine write_forcing_group
end module config_forcing
