!> Namelist group &bodies: rigid spheroids resolved by the immersed boundary in the resolved fluid,
!> in prescribed motion (&scene particles = 'prescribed') or free (&scene particles = 'free'), the
!> ghost-row solve, the load method and the uniform drive of the box (docs/decks.md, &bodies).
!>
!> The bodies are given in the deck (count, at most max_bodies, and the per-body arrays) or, any
!> number of them, in a body file (file: CSV, one body per line, read_body_file). Either way the
!> per-body arrays of bodies_config_t hold count bodies after reading.
!> Body n (1..count): shape(n), radius(n) (volume-equivalent, m), aspect_ratio(n), centre(:, n) (m),
!> axis(:, n) (its symmetry axis in the lab frame, any non-zero length), velocity(:, n) (m/s),
!> angular_velocity(:, n) (rad/s), oscillation_amplitude(:, n) (m) and oscillation_frequency(n) (Hz):
!> centre(t) = centre + velocity t + amplitude sin(2 pi f t).
!> geometry: the surface the ghost nodes see, 'analytic' (the spheroid) or 'mesh' (the icosphere of
!> mesh_level, the paper's fidelity); mesh_level is also the face count of the surface loads' face
!> sum (load_method = 'surface', computed and logged with either method).
module config_bodies
  use agglo_kinds, only: wp
  use file_system, only: longest_path
  use deck_file, only: deck_t, check_namelist_read, require_option, require_positive, require_nonnegative, &
                       require_range, int_text, real_text, text_file_load
  use error_handling, only: input_error
  implicit none
  private
  public :: bodies_config_t, read_bodies_group, read_body_file, check_bodies_group, write_bodies_group, max_bodies

  integer, parameter :: max_bodies = 16
  !> Finest icosphere: icosphere_mesh's max_icosphere_level (config/ does not use particles/; a unit
  !> test checks that the two agree).
  integer, parameter, public :: max_mesh_level = 4

  type :: bodies_config_t
    integer :: count = 0                                      !< bodies in the box (deck: 1..max_bodies)
    character(len=longest_path + 1) :: file = ''              !< the body file (CSV), instead of count and the arrays
    !> The arrays hold the bodies of file (read_body_file), not the deck's: the deck written back
    !> (run.nml) names the file and leaves them out.
    logical :: from_file = .false.
    ! Per body (the bodies are the first count elements: max_bodies of them from a deck, count from a body file):
    character(len=16), allocatable :: shape(:)                !< 'sphere' | 'needle' | 'disk' | 'spheroid'
    real(wp), allocatable :: radius(:)                        !< m, volume-equivalent radius
    real(wp), allocatable :: aspect_ratio(:)                  !< needle/disk: long/short (>= 1); spheroid: a/b
    real(wp), allocatable :: centre(:, :)                     !< (3, count) m
    real(wp), allocatable :: axis(:, :)                       !< (3, count) symmetry axis, lab frame; (0,0,0) = x
    real(wp), allocatable :: velocity(:, :)                   !< (3, count) m/s
    real(wp), allocatable :: angular_velocity(:, :)           !< (3, count) rad/s, lab frame, constant
    real(wp), allocatable :: oscillation_amplitude(:, :)      !< (3, count) m
    real(wp), allocatable :: oscillation_frequency(:)         !< Hz
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
  character(len=longest_path + 1) :: file
  real(wp) :: radius(max_bodies), aspect_ratio(max_bodies), centre(3, max_bodies), axis(3, max_bodies), &
              velocity(3, max_bodies), angular_velocity(3, max_bodies), oscillation_amplitude(3, max_bodies), &
              oscillation_frequency(max_bodies), ghost_tolerance, driving_force(3)
  namelist /bodies/ count, shape, radius, aspect_ratio, centre, axis, velocity, angular_velocity, &
                    oscillation_amplitude, oscillation_frequency, ghost_tolerance, max_sweeps, load_method, &
                    driving_force, geometry, mesh_level, compare_loads, file

contains

  !> The deck's values of one body where the deck gives none (docs/decks.md, &bodies).
  subroutine set_defaults()
    shape = 'sphere'; radius = 50.0e-6_wp; aspect_ratio = 5.0_wp; centre = 0.5e-3_wp; axis = 0
    velocity = 0; angular_velocity = 0; oscillation_amplitude = 0; oscillation_frequency = 0
  end subroutine set_defaults

  subroutine to_namelist(cfg)
    type(bodies_config_t), intent(in) :: cfg
    integer :: n
    call set_defaults()
    count = cfg%count
    file = cfg%file
    ! The bodies of a file stay in the file (count 0 in the deck).
    if (cfg%from_file) count = 0
    n = 0
    if (allocated(cfg%shape) .and. .not. cfg%from_file) n = min(size(cfg%shape), max_bodies)
    shape(1:n) = cfg%shape(1:n); radius(1:n) = cfg%radius(1:n); aspect_ratio(1:n) = cfg%aspect_ratio(1:n)
    centre(:, 1:n) = cfg%centre(:, 1:n); axis(:, 1:n) = cfg%axis(:, 1:n); velocity(:, 1:n) = cfg%velocity(:, 1:n)
    angular_velocity(:, 1:n) = cfg%angular_velocity(:, 1:n)
    oscillation_amplitude(:, 1:n) = cfg%oscillation_amplitude(:, 1:n)
    oscillation_frequency(1:n) = cfg%oscillation_frequency(1:n)
    ghost_tolerance = cfg%ghost_tolerance; max_sweeps = cfg%max_sweeps; load_method = cfg%load_method
    driving_force = cfg%driving_force; geometry = cfg%geometry; mesh_level = cfg%mesh_level
    compare_loads = cfg%compare_loads
  end subroutine to_namelist

  !> The deck's bodies and settings. The arrays keep all max_bodies elements the deck may give (the
  !> bodies are the first count of them), so the deck written back (run.nml) holds what was read.
  subroutine from_namelist(cfg)
    type(bodies_config_t), intent(inout) :: cfg
    cfg%count = count
    cfg%file = file
    cfg%shape = shape; cfg%radius = radius; cfg%aspect_ratio = aspect_ratio
    cfg%centre = centre; cfg%axis = axis; cfg%velocity = velocity
    cfg%angular_velocity = angular_velocity
    cfg%oscillation_amplitude = oscillation_amplitude; cfg%oscillation_frequency = oscillation_frequency
    cfg%ghost_tolerance = ghost_tolerance; cfg%max_sweeps = max_sweeps; cfg%load_method = load_method
    cfg%driving_force = driving_force; cfg%geometry = geometry; cfg%mesh_level = mesh_level
    cfg%compare_loads = compare_loads
  end subroutine from_namelist

  !> The group as the deck gives it; the bodies of &bodies file are read by read_body_file once the
  !> scene is known to use them (config_reader), so reading a deck never opens a file it names.
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

  !> The bodies of &bodies file, a CSV text file with one body per line:
  !>   shape, radius, aspect_ratio, x, y, z, axis_x, axis_y, axis_z, u, v, w [, omega_x, omega_y, omega_z]
  !> (shape as in the deck, quoted or not; radius the volume-equivalent radius in m; the centre in
  !> m; the symmetry axis in the lab frame, any length, 0 = x; the velocity in m/s; the angular
  !> velocity in rad/s, lab frame, 0 when left out). Blank lines and lines starting with '#' are
  !> skipped. No oscillation: a body of the file moves with constant velocities (prescribed) or
  !> under its loads (free). The values are checked with the deck's own (check_bodies_group).
  !> Collective: rank 0 reads the file, every rank parses the same lines and stops on the same error.
  subroutine read_body_file(cfg)
    type(bodies_config_t), intent(inout) :: cfg
    character(len=:), allocatable :: lines(:)
    character(len=:), allocatable :: place, name
    character(len=16) :: word
    real(wp) :: values(14)
    logical :: readable
    integer :: i, n, fields, ios
    name = '"'//trim(cfg%file)//'"'
    if (cfg%count /= 0) call input_error('bodies', 'count', int_text(cfg%count), '0 (not given) with &bodies file: '// &
        'the bodies are those of the file')
    call text_file_load(trim(cfg%file), lines, readable)
    if (.not. readable) call input_error('bodies', 'file', name, 'a readable text file '// &
        '(CSV, one body per line; docs/decks.md, &bodies)')
    n = count_bodies(lines)
    if (n == 0) call input_error('bodies', 'file', name//' (no body in it)', &
        'a CSV file with one body per line; docs/decks.md, &bodies')
    cfg%count = n
    cfg%from_file = .true.
    deallocate(cfg%shape, cfg%radius, cfg%aspect_ratio, cfg%centre, cfg%axis, cfg%velocity, cfg%angular_velocity, &
               cfg%oscillation_amplitude, cfg%oscillation_frequency)
    allocate(cfg%shape(n), cfg%radius(n), cfg%aspect_ratio(n), cfg%centre(3, n), cfg%axis(3, n), cfg%velocity(3, n), &
             cfg%angular_velocity(3, n), cfg%oscillation_amplitude(3, n), cfg%oscillation_frequency(n))
    cfg%oscillation_amplitude = 0
    cfg%oscillation_frequency = 0
    n = 0
    do i = 1, size(lines)
      if (skipped(lines(i))) cycle
      n = n + 1
      place = name//' line '//int_text(i)
      fields = 1 + count_commas(lines(i))
      if (fields /= 12 .and. fields /= 15) call input_error('bodies', 'file', place//': '//int_text(fields)// &
          ' fields', '12 or 15 comma-separated fields: shape, radius, aspect_ratio, x, y, z, axis_x, axis_y, axis_z, '// &
          'u, v, w [, omega_x, omega_y, omega_z]')
      values = 0
      read(lines(i), *, iostat=ios) word, values(1:fields - 1)
      if (ios /= 0) call input_error('bodies', 'file', place//': "'//trim(lines(i)(1:min(80, len(lines(i)))))//'"', &
          'a shape and '//int_text(fields - 1)//' numbers')
      if (.not. all(abs(values) < huge(1.0_wp))) call input_error('bodies', 'file', place, &
          'finite numbers (no NaN or Infinity)')
      cfg%shape(n) = word
      cfg%radius(n) = values(1)
      cfg%aspect_ratio(n) = values(2)
      cfg%centre(:, n) = values(3:5)
      cfg%axis(:, n) = values(6:8)
      cfg%velocity(:, n) = values(9:11)
      cfg%angular_velocity(:, n) = values(12:14)
    end do
  contains
    logical function skipped(line)
      character(len=*), intent(in) :: line
      character(len=:), allocatable :: text
      text = adjustl(line)
      skipped = len_trim(text) == 0
      if (.not. skipped) skipped = text(1:1) == '#'
    end function skipped

    integer function count_bodies(lines)
      character(len=*), intent(in) :: lines(:)
      integer :: k
      count_bodies = 0
      do k = 1, size(lines)
        if (.not. skipped(lines(k))) count_bodies = count_bodies + 1
      end do
    end function count_bodies

    integer function count_commas(line)
      character(len=*), intent(in) :: line
      integer :: k
      count_commas = 0
      do k = 1, len_trim(line)
        if (line(k:k) == ',') count_commas = count_commas + 1
      end do
    end function count_commas
  end subroutine read_body_file

  subroutine check_bodies_group(cfg)
    type(bodies_config_t), intent(in) :: cfg
    integer :: n
    character(len=:), allocatable :: index
    ! A body file holds any number of bodies; the deck's arrays max_bodies.
    if (len_trim(cfg%file) == 0 .and. (cfg%count < 1 .or. cfg%count > max_bodies)) call input_error('bodies', &
        'count', int_text(cfg%count), '1 to '//int_text(max_bodies))
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
