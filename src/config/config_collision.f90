!> Namelist group &collision: hard-body collisions (detection distance and impulse model) and the
!> optional sub-grid lubrication (particles/lubrication.f90; off by default: the paper has none).
!> Defaults: the paper's model (section 2.2.4, Eq. 24) with Table 1's restitution.
module config_collision
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_nonnegative, require_range, &
                       require_option
  implicit none
  private
  public :: collision_config_t, read_collision_group, check_collision_group, write_collision_group

  type :: collision_config_t
    real(wp) :: restitution = 0.4_wp                !< normal restitution coefficient e (Table 1)
    character(len=16) :: model = 'paper'            !< 'paper' | 'frictionless' | 'coulomb'
    real(wp) :: friction_coefficient = 0.1_wp       !< Coulomb friction mu_c (model = 'coulomb' only)
    real(wp) :: detection_floor = 1.0e-9_wp         !< m, smallest detection distance
    real(wp) :: detection_factor = 1.0_wp           !< detection distance = max(floor, factor v_n dt)
    logical :: lubrication = .false.                !< sub-grid normal lubrication force
    !> hand-over gap h_out in cells of &grid (the smallest spacing): the resolved fluid carries the
    !> squeeze force above it; half a cell, where the resolved force stops rising (docs/validation.md,
    !> "Lubrication": 1 cell counts the squeeze the grid still carries twice)
    real(wp) :: lubrication_handover = 0.5_wp
    real(wp) :: lubrication_roughness = 1.0e-9_wp   !< m, h_in: the force saturates below this gap
  end type collision_config_t

  real(wp) :: restitution, friction_coefficient, detection_floor, detection_factor, lubrication_handover, &
              lubrication_roughness
  character(len=16) :: model
  logical :: lubrication
  namelist /collision/ restitution, model, friction_coefficient, detection_floor, detection_factor, lubrication, &
                       lubrication_handover, lubrication_roughness

contains

  subroutine to_namelist(cfg)
    type(collision_config_t), intent(in) :: cfg
    restitution = cfg%restitution; model = cfg%model; friction_coefficient = cfg%friction_coefficient
    detection_floor = cfg%detection_floor; detection_factor = cfg%detection_factor
    lubrication = cfg%lubrication; lubrication_handover = cfg%lubrication_handover
    lubrication_roughness = cfg%lubrication_roughness
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(collision_config_t), intent(inout) :: cfg
    cfg%restitution = restitution; cfg%model = model; cfg%friction_coefficient = friction_coefficient
    cfg%detection_floor = detection_floor; cfg%detection_factor = detection_factor
    cfg%lubrication = lubrication; cfg%lubrication_handover = lubrication_handover
    cfg%lubrication_roughness = lubrication_roughness
  end subroutine from_namelist

  subroutine read_collision_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(collision_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=collision, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'collision', ios, message)
    call from_namelist(cfg)
  end subroutine read_collision_group

  subroutine check_collision_group(cfg)
    type(collision_config_t), intent(in) :: cfg
    call require_range('collision', 'restitution', cfg%restitution, 0.0_wp, 1.0_wp)
    call require_option('collision', 'model', cfg%model, [character(len=16) :: 'paper', 'frictionless', 'coulomb'])
    call require_nonnegative('collision', 'friction_coefficient', cfg%friction_coefficient)
    call require_positive('collision', 'detection_floor', cfg%detection_floor)
    call require_positive('collision', 'detection_factor', cfg%detection_factor)
    call require_positive('collision', 'lubrication_handover', cfg%lubrication_handover)
    call require_positive('collision', 'lubrication_roughness', cfg%lubrication_roughness)
  end subroutine check_collision_group

  subroutine write_collision_group(unit, cfg)
    integer, intent(in) :: unit
    type(collision_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=collision)
  end subroutine write_collision_group
end module config_collision
