!> Namelist group &pair: the two-particle set-up of the paper's protocol (docs/design.md).
!> Both particles have the same shape; the pair is placed with an exact surface gap along its
!> closest-approach vector and each particle moves towards the other at relative_speed / 2.
module config_pair
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_option, require_range, real_text
  use error_handling, only: input_error
  implicit none
  private
  public :: pair_config_t, read_pair_group, check_pair_group, write_pair_group

  real(wp), parameter :: max_aspect_ratio = 20.0_wp   !< largest validated long/short semi-axis ratio

  type :: pair_config_t
    character(len=16) :: shape = 'disk'           !< 'sphere' | 'needle' | 'disk' | 'spheroid'
    real(wp) :: aspect_ratio = 5.0_wp             !< needle a/b, disk b/a (both >= 1); 'spheroid': a/b
    real(wp) :: radius = 50.0e-6_wp               !< m, volume-equivalent radius r (a b^2 = r^3)
    real(wp) :: density = 2710.0_wp               !< kg/m^3, calcite (paper, Table 1)
    character(len=16) :: orientation = 'random'   !< 'random' (uniform, from &run seed) | 'given'
    real(wp) :: axis1(3) = [0.0_wp, 0.0_wp, 1.0_wp]   !< rotation axis of particle 1 ('given')
    real(wp) :: angle1 = 0.0_wp                   !< rad, rotation angle of particle 1 ('given')
    real(wp) :: axis2(3) = [0.0_wp, 0.0_wp, 1.0_wp]
    real(wp) :: angle2 = 0.0_wp
    character(len=16) :: approach = 'random'      !< direction from 1 to 2 before gap placement: 'random' | 'given'
    real(wp) :: approach_direction(3) = [1.0_wp, 0.0_wp, 0.0_wp]
    real(wp) :: gap = 5.0e-6_wp                   !< m, initial surface gap along the closest-approach vector
    real(wp) :: relative_speed = 0.875e-3_wp      !< m/s, initial approach speed (each particle +-v/2)
    character(len=16) :: centre = 'given'         !< pair centre: 'given' | 'random' (uniform in the box)
    real(wp) :: centre_position(3) = [0.5e-3_wp, 0.5e-3_wp, 0.5e-3_wp]  !< m
    real(wp) :: box_length = 1.0e-3_wp            !< m, box for centre = 'random'
    logical :: mirror_first_collision = .true.    !< end at twice the first-collision time (paper)
    character(len=16) :: end_rule = 'settled'     !< 'settled': past that end until the outcome is settled | 'paper'
    !> s, the paper's fixed end (the chaotic protocol's 3 ms); 0: &run end_time (which caps every rule)
    real(wp) :: paper_end_time = 0.0_wp
    !> s, how long a pair must stay bound for its 'agglomerated' to be settled (docs/theory.md, "Run outcome")
    real(wp) :: settle_time = 1.0e-3_wp
    character(len=16) :: integrator = 'euler'     !< rigid-body update: 'euler' (paper) | 'verlet' (2nd order)
    !> Resolved fluid: the start velocities on top of the fluid's at each centre (and the angular
    !> velocity its local (1/2) curl u); centre = 'random' draws in the fluid's box (box_length unused)
    logical :: relative_to_fluid = .false.
    !> When the particles start to feel the hydrodynamic loads: 'start' | 'first_contact' (after their
    !> first collision; the fluid still sees the moving bodies from the start)
    character(len=16) :: hydrodynamics_from = 'start'
    !> m/s^2: gravity on the resolved particles (their net weight; the box's mean pressure gradient
    !> balances it), &scene particle_coupling = 'resolved' only
    real(wp) :: gravity(3) = 0.0_wp
  end type pair_config_t

  character(len=16) :: shape, orientation, approach, centre, integrator, end_rule, hydrodynamics_from
  real(wp) :: aspect_ratio, radius, density, axis1(3), angle1, axis2(3), angle2, approach_direction(3), &
              gap, relative_speed, centre_position(3), box_length, gravity(3), paper_end_time, settle_time
  logical :: mirror_first_collision, relative_to_fluid
  namelist /pair/ shape, aspect_ratio, radius, density, orientation, axis1, angle1, axis2, angle2, approach, &
                  approach_direction, gap, relative_speed, centre, centre_position, box_length, mirror_first_collision, &
                  integrator, end_rule, relative_to_fluid, hydrodynamics_from, &
                  gravity, paper_end_time, settle_time

contains

  subroutine to_namelist(cfg)
    type(pair_config_t), intent(in) :: cfg
    shape = cfg%shape; aspect_ratio = cfg%aspect_ratio; radius = cfg%radius; density = cfg%density
    orientation = cfg%orientation; axis1 = cfg%axis1; angle1 = cfg%angle1; axis2 = cfg%axis2
    angle2 = cfg%angle2; approach = cfg%approach; approach_direction = cfg%approach_direction
    gap = cfg%gap; relative_speed = cfg%relative_speed; centre = cfg%centre
    centre_position = cfg%centre_position; box_length = cfg%box_length
    mirror_first_collision = cfg%mirror_first_collision; integrator = cfg%integrator; end_rule = cfg%end_rule
    relative_to_fluid = cfg%relative_to_fluid; hydrodynamics_from = cfg%hydrodynamics_from
    gravity = cfg%gravity; paper_end_time = cfg%paper_end_time; settle_time = cfg%settle_time
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(pair_config_t), intent(inout) :: cfg
    cfg%shape = shape; cfg%aspect_ratio = aspect_ratio; cfg%radius = radius; cfg%density = density
    cfg%orientation = orientation; cfg%axis1 = axis1; cfg%angle1 = angle1; cfg%axis2 = axis2
    cfg%angle2 = angle2; cfg%approach = approach; cfg%approach_direction = approach_direction
    cfg%gap = gap; cfg%relative_speed = relative_speed; cfg%centre = centre
    cfg%centre_position = centre_position; cfg%box_length = box_length
    cfg%mirror_first_collision = mirror_first_collision; cfg%integrator = integrator; cfg%end_rule = end_rule
    cfg%relative_to_fluid = relative_to_fluid; cfg%hydrodynamics_from = hydrodynamics_from
    cfg%gravity = gravity; cfg%paper_end_time = paper_end_time; cfg%settle_time = settle_time
  end subroutine from_namelist

  subroutine read_pair_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(pair_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=pair, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'pair', ios, message)
    call from_namelist(cfg)
  end subroutine read_pair_group

  subroutine check_pair_group(cfg)
    type(pair_config_t), intent(in) :: cfg
    call require_option('pair', 'shape', cfg%shape, [character(len=8) :: 'sphere', 'needle', 'disk', 'spheroid'])
    call require_positive('pair', 'aspect_ratio', cfg%aspect_ratio)
    ! Upper bound: closest points (tests/unit/test_closest_points.f90) and the Stokes resistance are
    ! validated for long/short semi-axis ratios up to 20; beyond it neither is checked.
    if ((cfg%shape == 'needle' .or. cfg%shape == 'disk') .and. &
        .not. (cfg%aspect_ratio > 1.0_wp .and. cfg%aspect_ratio <= max_aspect_ratio)) call input_error('pair', &
        'aspect_ratio', real_text(cfg%aspect_ratio), '> 1 and <= '//real_text(max_aspect_ratio)//' for shape = '''// &
        trim(cfg%shape)//''' (long over short semi-axis; use shape = ''spheroid'' for a/b on either side of 1)')
    if (cfg%shape == 'spheroid') call require_range('pair', 'aspect_ratio', cfg%aspect_ratio, &
        1.0_wp / max_aspect_ratio, max_aspect_ratio)
    call require_positive('pair', 'radius', cfg%radius)
    call require_positive('pair', 'density', cfg%density)
    call require_option('pair', 'orientation', cfg%orientation, [character(len=8) :: 'random', 'given'])
    if (cfg%orientation == 'given') then
      if (.not. (norm2(cfg%axis1) > 0.0_wp)) call input_error('pair', 'axis1', '(0, 0, 0)', 'a non-zero vector')
      if (.not. (norm2(cfg%axis2) > 0.0_wp)) call input_error('pair', 'axis2', '(0, 0, 0)', 'a non-zero vector')
    end if
    call require_option('pair', 'approach', cfg%approach, [character(len=8) :: 'random', 'given'])
    if (cfg%approach == 'given' .and. .not. (norm2(cfg%approach_direction) > 0.0_wp)) &
        call input_error('pair', 'approach_direction', '(0, 0, 0)', 'a non-zero vector')
    call require_positive('pair', 'gap', cfg%gap)
    if (.not. (cfg%relative_speed >= 0.0_wp)) call input_error('pair', 'relative_speed', &
        real_text(cfg%relative_speed), '>= 0')
    call require_option('pair', 'centre', cfg%centre, [character(len=8) :: 'given', 'random'])
    call require_positive('pair', 'box_length', cfg%box_length)
    call require_option('pair', 'integrator', cfg%integrator, [character(len=8) :: 'euler', 'verlet'])
    call require_option('pair', 'end_rule', cfg%end_rule, [character(len=8) :: 'settled', 'paper'])
    if (.not. (cfg%paper_end_time >= 0.0_wp)) call input_error('pair', 'paper_end_time', &
        real_text(cfg%paper_end_time), '>= 0 s (0: &run end_time)')
    if (.not. (cfg%settle_time >= 0.0_wp)) call input_error('pair', 'settle_time', real_text(cfg%settle_time), '>= 0 s')
    call require_option('pair', 'hydrodynamics_from', cfg%hydrodynamics_from, &
                        [character(len=13) :: 'start', 'first_contact'])
  end subroutine check_pair_group

  subroutine write_pair_group(unit, cfg)
    integer, intent(in) :: unit
    type(pair_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=pair)
  end subroutine write_pair_group
end module config_pair
