!> Namelist group &collision: hard-body collisions (stub: extended by the particle work).
module config_collision
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive
  implicit none
  private
  public :: collision_config_t, read_collision_group, check_collision_group, write_collision_group

  type :: collision_config_t
    real(wp) :: restitution = 0.4_wp   !< normal restitution coefficient (paper, Table 1)
  end type collision_config_t

  real(wp) :: restitution
  namelist /collision/ restitution

contains

  subroutine to_namelist(cfg)
    type(collision_config_t), intent(in) :: cfg
    restitution = cfg%restitution
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(collision_config_t), intent(inout) :: cfg
    cfg%restitution = restitution
  end subroutine from_namelist

  subroutine read_collision_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(collision_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=collision, iostat=ios, iomsg=message)
    call check_namelist_read('collision', ios, message)
    call from_namelist(cfg)
  end subroutine read_collision_group

  subroutine check_collision_group(cfg)
    type(collision_config_t), intent(in) :: cfg
    call require_positive('collision', 'restitution', cfg%restitution)
  end subroutine check_collision_group

  subroutine write_collision_group(unit, cfg)
    integer, intent(in) :: unit
    type(collision_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=collision)
  end subroutine write_collision_group
end module config_collision
