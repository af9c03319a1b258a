!> Namelist group &pair: the particle pair set-up of the paper's protocol (stub: extended by the particle work).
module config_pair
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_option
  implicit none
  private
  public :: pair_config_t, read_pair_group, check_pair_group, write_pair_group

  type :: pair_config_t
    real(wp) :: radius = 50.0e-6_wp   !< m, volume-equivalent radius
    character(len=16) :: integrator = 'euler'   !< rigid-body update: 'euler' (paper) | 'verlet' (2nd order)
  end type pair_config_t

  real(wp) :: radius
  character(len=16) :: integrator
  namelist /pair/ radius, integrator

contains

  subroutine to_namelist(cfg)
    type(pair_config_t), intent(in) :: cfg
    radius = cfg%radius
    integrator = cfg%integrator
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(pair_config_t), intent(inout) :: cfg
    cfg%radius = radius
    cfg%integrator = integrator
  end subroutine from_namelist

  subroutine read_pair_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(pair_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=pair, iostat=ios, iomsg=message)
    call check_namelist_read('pair', ios, message)
    call from_namelist(cfg)
  end subroutine read_pair_group

  subroutine check_pair_group(cfg)
    type(pair_config_t), intent(in) :: cfg
    call require_positive('pair', 'radius', cfg%radius)
    call require_option('pair', 'integrator', cfg%integrator, [character(len=16) :: 'euler', 'verlet'])
  end subroutine check_pair_group

  subroutine write_pair_group(unit, cfg)
    integer, intent(in) :: unit
    type(pair_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=pair)
  end subroutine write_pair_group
end module config_pair
