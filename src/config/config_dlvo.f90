!> Namelist group &dlvo: DLVO interaction (stub: extended by the particle work).
module config_dlvo
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive
  implicit none
  private
  public :: dlvo_config_t, read_dlvo_group, check_dlvo_group, write_dlvo_group

  type :: dlvo_config_t
    real(wp) :: hamaker = 22.3e-21_wp   !< J, Hamaker constant (paper, Table 1)
  end type dlvo_config_t

  real(wp) :: hamaker
  namelist /dlvo/ hamaker

contains

  subroutine to_namelist(cfg)
    type(dlvo_config_t), intent(in) :: cfg
    hamaker = cfg%hamaker
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(dlvo_config_t), intent(inout) :: cfg
    cfg%hamaker = hamaker
  end subroutine from_namelist

  subroutine read_dlvo_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(dlvo_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=dlvo, iostat=ios, iomsg=message)
    call check_namelist_read('dlvo', ios, message)
    call from_namelist(cfg)
  end subroutine read_dlvo_group

  subroutine check_dlvo_group(cfg)
    type(dlvo_config_t), intent(in) :: cfg
    call require_positive('dlvo', 'hamaker', cfg%hamaker)
  end subroutine check_dlvo_group

  subroutine write_dlvo_group(unit, cfg)
    integer, intent(in) :: unit
    type(dlvo_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=dlvo)
  end subroutine write_dlvo_group
end module config_dlvo
