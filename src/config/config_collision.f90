!> Namelist group &collision: hard-body collisions (detection distance and impulse model) and the
!> optional sub-grid lubrication (particles/lubrication.f90; off by default: the paper has none).
!> Defaults: the paper's model (section 2.2.4, Eq. 24) with Table 1's restitution.
module config_collision
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_nonnegative, require_range, &
                       require_option, require_positive_int
  implicit none
  private
  public :: collision_config_t, read_collision_group, check_collision_group, write_collision_group, &
            default_lubrication_handover

  type :: collision_config_t
    real(wp) :: restitution = 0.4_wp                !< normal restitution coefficient e (Table 1)
    character(len=16) :: model = 'paper'            !< 'paper' | 'frictionless' | 'coulomb'
    real(wp) :: friction_coefficient = 0.1_wp       !< Coulomb friction mu_c (model = 'coulomb' only)
    real(wp) :: detection_floor = 1.0e-9_wp         !< m, smallest detection distance
    real(wp) :: detection_factor = 1.0_wp           !< detection distance = max(floor, factor v_n dt)
    logical :: lubrication = .false.                !< sub-grid normal lubrication force
    !> hand-over gap h_out in cells of &grid (the smallest spacing): the resolved fluid carries the
    !> squeeze force above it; 0 (the default): default_lubrication_handover of the scene's pressure
    !> scheme, set when the deck is parsed (config_reader)
    real(wp) :: lubrication_handover = 0.0_wp
    real(wp) :: lubrication_roughness = 1.0e-9_wp   !< m, h_in: the force saturates below this gap
    !> the tangential and rotational log(1/xi) terms too (particles/lubrication.f90; docs/theory.md)
    logical :: lubrication_tangential = .false.
    !> cap on the sequential-impulse sweeps of one interaction (several simultaneous contacts)
    integer :: max_impulse_sweeps = 200
  end type collision_config_t

  real(wp) :: restitution, friction_coefficient, detection_floor, detection_factor, lubrication_handover, &
              lubrication_roughness
  character(len=16) :: model
  logical :: lubrication, lubrication_tangential
  integer :: max_impulse_sweeps
  namelist /collision/ restitution, model, friction_coefficient, detection_floor, detection_factor, lubrication, &
                       lubrication_handover, lubrication_roughness, lubrication_tangential, max_impulse_sweeps

contains

  !> The hand-over gap (cells) of the scene's rung (docs/theory.md, "Sub-grid lubrication").
  !> Resolved particles: where the resolved squeeze force of the immersed boundary stops following
  !> Brenner's (1961) exact force of two spheres (docs/studies/validation.md, "Lubrication"). With
  !> the pressure-free projection (&fluid pressure_scheme = 'non_incremental', the decks') the
  !> resolved force falls behind the exact one from about a cell (-10% at 0.75 cell, -25% at 0.5
  !> cell, D/dx = 8, nu dt/dx^2 = 0.079): 0.75 cell, with which the total stays within +4% below it.
  !> With the incremental pressure it follows to half a cell (and overshoots by about 20% between 1
  !> and 0.5 cell, which a larger hand-over would count twice): 0.5 cell. The 'stokes' scene and
  !> point particles resolve no squeeze flow at all (isolated-body resistances): the model acts from
  !> one particle radius (&pair radius) on, radius / spacing cells, which keeps the near-contact
  !> mobility of two spheres within 2% of the exact one below a hundredth of a radius
  !> (docs/studies/validation.md, "Free approach under a constant force").
  pure real(wp) function default_lubrication_handover(fluid, particle_coupling, pressure_scheme, radius, spacing) &
      result(cells)
    character(len=*), intent(in) :: fluid               !< &scene fluid
    character(len=*), intent(in) :: particle_coupling   !< &scene particle_coupling
    character(len=*), intent(in) :: pressure_scheme     !< &fluid pressure_scheme
    real(wp), intent(in) :: radius                      !< m, &pair radius
    real(wp), intent(in) :: spacing                     !< m, the smallest &grid cell edge (> 0)
    cells = 0.5_wp
    if (fluid == 'resolved' .and. particle_coupling == 'resolved' .and. pressure_scheme == 'non_incremental') &
      cells = 0.75_wp
    if (fluid == 'stokes' .or. (fluid == 'resolved' .and. particle_coupling == 'point')) cells = radius / spacing
  end function default_lubrication_handover

  subroutine to_namelist(cfg)
    type(collision_config_t), intent(in) :: cfg
    restitution = cfg%restitution; model = cfg%model; friction_coefficient = cfg%friction_coefficient
    detection_floor = cfg%detection_floor; detection_factor = cfg%detection_factor
    lubrication = cfg%lubrication; lubrication_handover = cfg%lubrication_handover
    lubrication_roughness = cfg%lubrication_roughness
    lubrication_tangential = cfg%lubrication_tangential
    max_impulse_sweeps = cfg%max_impulse_sweeps
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(collision_config_t), intent(inout) :: cfg
    cfg%restitution = restitution; cfg%model = model; cfg%friction_coefficient = friction_coefficient
    cfg%detection_floor = detection_floor; cfg%detection_factor = detection_factor
    cfg%lubrication = lubrication; cfg%lubrication_handover = lubrication_handover
    cfg%lubrication_roughness = lubrication_roughness
    cfg%lubrication_tangential = lubrication_tangential
    cfg%max_impulse_sweeps = max_impulse_sweeps
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
    call require_positive_int('collision', 'max_impulse_sweeps', cfg%max_impulse_sweeps)
  end subroutine check_collision_group

  subroutine write_collision_group(unit, cfg)
    integer, intent(in) :: unit
    type(collision_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=collision)
  end subroutine write_collision_group
end module config_collision
