!> Namelist group &bodies: rigid spheroids in prescribed motion resolved by the immersed boundary
!> (&scene fluid = 'resolved', particles = 'prescribed'), the ghost-row solve, the load method and
!> the uniform drive of the box (docs/decks.md, &bodies).
!>
!> Body n (1..count): shape(n), radius(n) (volume-equivalent, m), aspect_ratio(n), centre(:, n) (m),
!> axis(:, n) (its symmetry axis in the lab frame, any non-zero length), velocity(:, n) (m/s),
!> angular_velocity(:, n) (rad/s), oscillation_amplitude(:, n) (m) and oscillation_frequency(n) (Hz):
!> centre(t) = centre + velocity t + amplitude sin(2 pi f t).
!> geometry: the surface the ghost nodes see, 'analytic' (the spheroid) or 'mesh' (the icosphere of
!> mesh_level, the paper's fidelity); mesh_level is also the face count of the surface loads' face
!> sum (load_method = 'surface', computed and logged with either method).
module config_bodies
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_option, require_positive, require_nonnegative, &
                       require_range, int_text, real_text
  use error_handling, only: input_error
  implicit none
  private
  public :: bodies_config_t, read_bodies_group, check_bodies_group, write_bodies_group, max_bodies

  integer, parameter :: max_bodies = 16
  !> Finest icosphere: icosphere_mesh's max_icosphere_level (config/ does not use particles/; a unit
  !> test checks that the two agree).
  integer, parameter, public :: max_mesh_level = 4

  type :: bodies_config_t
    integer :: count = 0                                      !< bodies in the box (1..max_bodies)
    character(len=16) :: shape(max_bodies) = 'sphere'         !< 'sphere' | 'needle' | 'disk' | 'spheroid'
    real(wp) :: radius(max_bodies) = 50.0e-6_wp               !< m, volume-equivalent radius
    real(wp) :: aspect_ratio(max_bodies) = 5.0_wp             !< needle/disk: long/short (>= 1); spheroid: a/b
    real(wp) :: centre(3, max_bodies) = 0.5e-3_wp             !< m
    real(wp) :: axis(3, max_bodies) = 0                       !< symmetry axis, lab frame; (0,0,0) = x
    real(wp) :: velocity(3, max_bodies) = 0                   !< m/s
    real(wp) :: angular_velocity(3, max_bodies) = 0           !< rad/s, lab frame, constant
    real(wp) :: oscillation_amplitude(3, max_bodies) = 0      !< m
    real(wp) :: oscillation_frequency(max_bodies) = 0         !< Hz
    real(wp) :: ghost_tolerance = 1.0e-12_wp                  !< ghost-row sweeps stop below this relative change
    !> Sweeps before the run stops (implicit coupling). One body takes at most 8; a pair near contact
    !> far more, growing as the gap closes (up to 157 measured, docs/decks.md, &bodies): a run must
    !> not stop for that, only for rows that do not converge at all.
    integer :: max_sweeps = 1000
    character(len=16) :: load_method = 'momentum'             !< 'momentum' | 'surface' (the face sum)
    character(len=16) :: geometry = 'analytic'                !< 'analytic' | 'mesh' (ghost nodes' surface)
    integer :: mesh_level = 2                                 !< icosphere subdivisions: 20 4^level faces (2: 320)
    logical :: compare_loads = .false.                        !< also the face sum with load_method = 'momentum'
    real(wp) :: driving_force(3) = 0                          !< N/m^3, uniform body force (mean pressure gradient)
  end type bodies_config_t

  integer :: count, max_sweeps, mesh_level
  logical :: compare_loads
  character(len=16) :: shape(max_bodies), load_method, geometry
  real(wp) :: radius(max_bodies), aspect_ratio(max_bodies), centre(3, max_bodies), axis(3, max_bodies), &
              velocity(3, max_bodies), angular_velocity(3, max_bodies), oscillation_amplitude(3, max_bodies), &
              oscillation_frequency(max_bodies), ghost_tolerance, driving_force(3)
  namelist /bodies/ count, shape, radius, aspect_ratio, centre, axis, velocity, angular_velocity, &
                    oscillation_amplitude, oscillation_frequency, ghost_tolerance, max_sweeps, load_method, &
                    driving_force, geometry, mesh_level, compare_loads

contains

  subroutine to_namelist(cfg)
    type(bodies_config_t), intent(in) :: cfg
    count = cfg%count; shape = cfg%shape; radius = cfg%radius; aspect_ratio = cfg%aspect_ratio
    centre = cfg%centre; axis = cfg%axis; velocity = cfg%velocity; angular_velocity = cfg%angular_velocity
    oscillation_amplitude = cfg%oscillation_amplitude; oscillation_frequency = cfg%oscillation_frequency
    ghost_tolerance = cfg%ghost_tolerance; max_sweeps = cfg%max_sweeps; load_method = cfg%load_method
    driving_force = cfg%driving_force; geometry = cfg%geometry; mesh_level = cfg%mesh_level
    compare_loads = cfg%compare_loads
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(bodies_config_t), intent(inout) :: cfg
    cfg%count = count; cfg%shape = shape; cfg%radius = radius; cfg%aspect_ratio = aspect_ratio
    cfg%centre = centre; cfg%axis = axis; cfg%velocity = velocity; cfg%angular_velocity = angular_velocity
    cfg%oscillation_amplitude = oscillation_amplitude; cfg%oscillation_frequency = oscillation_frequency
    cfg%ghost_tolerance = ghost_tolerance; cfg%max_sweeps = max_sweeps; cfg%load_method = load_method
    cfg%driving_force = driving_force; cfg%geometry = geometry; cfg%mesh_level = mesh_level
    cfg%compare_loads = compare_loads
  end subroutine from_namelist

  subroutine read_bodies_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(bodies_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=bodies, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'bodies', ios, message)
    call from_namelist(cfg)
  end subroutine read_bodies_group

  subroutine check_bodies_group(cfg)
    type(bodies_config_t), intent(in) :: cfg
    integer :: n
    character(len=:), allocatable :: index
    if (cfg%count < 1 .or. cfg%count > max_bodies) call input_error('bodies', 'count', int_text(cfg%count), &
        '1 to '//int_text(max_bodies))
    do n = 1, cfg%count
      index = '('//int_text(n)//')'
      call require_option('bodies', 'shape'//index, cfg%shape(n), &
                          [character(len=8) :: 'sphere', 'needle', 'disk', 'spheroid'])
      call require_positive('bodies', 'radius'//index, cfg%radius(n))
      select case (trim(cfg%shape(n)))
      case ('needle', 'disk')
        if (.not. (cfg%aspect_ratio(n) >= 1.0_wp)) call input_error('bodies', 'aspect_ratio'//index, &
            real_text(cfg%aspect_ratio(n)), '>= 1 for '//trim(cfg%shape(n))//' (long over short semi-axis)')
      case ('spheroid')
        call require_positive('bodies', 'aspect_ratio'//index, cfg%aspect_ratio(n))
      end select
      call require_nonnegative('bodies', 'oscillation_frequency'//index, cfg%oscillation_frequency(n))
      if (.not. all(abs(cfg%centre(:, n)) < huge(1.0_wp))) call input_error('bodies', 'centre(:, '//int_text(n)//')', &
          'not finite', 'finite positions (m, in the box of &grid)')
    end do
    call require_range('bodies', 'ghost_tolerance', cfg%ghost_tolerance, 1.0e-15_wp, 1.0e-3_wp)
    if (cfg%max_sweeps < 1 .or. cfg%max_sweeps > 10000) call input_error('bodies', 'max_sweeps', &
        int_text(cfg%max_sweeps), '1 to 10000')
    call require_option('bodies', 'load_method', cfg%load_method, [character(len=8) :: 'momentum', 'surface'])
    call require_option('bodies', 'geometry', cfg%geometry, [character(len=8) :: 'analytic', 'mesh'])
    if (cfg%mesh_level < 0 .or. cfg%mesh_level > max_mesh_level) call input_error('bodies', 'mesh_level', &
        int_text(cfg%mesh_level), '0 to '//int_text(max_mesh_level)//' (icosphere subdivisions, 20 4^level faces: '// &
        '20 to '//int_text(20 * 4**max_mesh_level)//'; 2 = 320 faces, the paper''s mesh)')
    if (.not. all(abs(cfg%driving_force) < huge(1.0_wp))) call input_error('bodies', 'driving_force', &
        'not finite', 'finite N/m^3')
  end subroutine check_bodies_group

  subroutine write_bodies_group(unit, cfg)
    integer, intent(in) :: unit
    type(bodies_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=bodies)
  end subroutine write_bodies_group
end module config_bodies
