!> Namelist group &suspension: the bodies of &scene particles = 'suspension', placed at random in
!> the periodic box of &grid (module suspension_placement; docs/theory.md, "Suspension placement").
!> Up to max_species species, each a shape, a volume-equivalent radius, an aspect ratio and either a
!> count or a volume fraction; the species in use are those with a shape.
module config_suspension
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_option, require_positive, require_nonnegative, &
                       int_text, real_text
  use error_handling, only: input_error
  use config_shapes, only: deck_semi_axes
  implicit none
  private
  public :: suspension_config_t, read_suspension_group, check_suspension_group, write_suspension_group, &
            max_species, species_count, species_semi_axes

  integer, parameter :: max_species = 8

  type :: suspension_config_t
    !> 'sphere' | 'needle' | 'disk' | 'spheroid' per species; '' = no such species
    character(len=16) :: shape(max_species) = [character(len=16) :: 'sphere', '', '', '', '', '', '', '']
    real(wp) :: radius(max_species) = 50.0e-6_wp          !< m, volume-equivalent radius r of each species
    real(wp) :: aspect_ratio(max_species) = 5.0_wp        !< needle/disk: long/short (>= 1); spheroid: a/b
    integer :: count(max_species) = 0                     !< bodies of each species (or volume_fraction)
    real(wp) :: volume_fraction(max_species) = 0.0_wp     !< volume fraction of each species (or count)
    real(wp) :: min_gap = 2.0e-6_wp                       !< m, smallest surface gap between two placed bodies
    real(wp) :: velocity_rms = 0.0_wp                     !< m/s, rms of each component of the random velocity
    integer :: max_attempts = 10000                       !< random tries per body before the placement stops
    real(wp) :: memory_limit = 0.0_wp                     !< GiB the bodies may take; 0 = the machine's available
    logical :: ghost = .false.                            !< ghost collisions: counted, no impulse, no DLVO
  end type suspension_config_t

  character(len=16) :: shape(max_species)
  real(wp) :: radius(max_species), aspect_ratio(max_species), volume_fraction(max_species), min_gap, velocity_rms, &
              memory_limit
  integer :: count(max_species), max_attempts
  logical :: ghost
  namelist /suspension/ shape, radius, aspect_ratio, count, volume_fraction, min_gap, velocity_rms, max_attempts, &
                        memory_limit, ghost

contains

  subroutine to_namelist(cfg)
    type(suspension_config_t), intent(in) :: cfg
    shape = cfg%shape; radius = cfg%radius; aspect_ratio = cfg%aspect_ratio; count = cfg%count
    volume_fraction = cfg%volume_fraction; min_gap = cfg%min_gap; velocity_rms = cfg%velocity_rms
    max_attempts = cfg%max_attempts; memory_limit = cfg%memory_limit; ghost = cfg%ghost
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(suspension_config_t), intent(inout) :: cfg
    cfg%shape = shape; cfg%radius = radius; cfg%aspect_ratio = aspect_ratio; cfg%count = count
    cfg%volume_fraction = volume_fraction; cfg%min_gap = min_gap; cfg%velocity_rms = velocity_rms
    cfg%max_attempts = max_attempts; cfg%memory_limit = memory_limit; cfg%ghost = ghost
  end subroutine from_namelist

  subroutine read_suspension_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(suspension_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=suspension, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'suspension', ios, message)
    call from_namelist(cfg)
  end subroutine read_suspension_group

  !> The species in use: the leading entries with a shape (a gap in the list is refused).
  pure integer function species_count(cfg)
    type(suspension_config_t), intent(in) :: cfg
    species_count = 0
    do while (species_count < max_species)
      if (len_trim(cfg%shape(species_count + 1)) == 0) exit
      species_count = species_count + 1
    end do
  end function species_count

  !> Semi-axes (a along the symmetry axis, b) of species k, a b^2 = r^3 (as module spheroid makes them).
  pure function species_semi_axes(cfg, k) result(axes)
    type(suspension_config_t), intent(in) :: cfg
    integer, intent(in) :: k
    real(wp) :: axes(2)
    axes = deck_semi_axes(cfg%shape(k), cfg%radius(k), cfg%aspect_ratio(k))
  end function species_semi_axes

  subroutine check_suspension_group(cfg)
    type(suspension_config_t), intent(in) :: cfg
    integer :: k, n
    character(len=:), allocatable :: index
    n = species_count(cfg)
    if (n == 0) call input_error('suspension', 'shape(1)', '''''', 'a shape for at least one species: '// &
        '''sphere'', ''needle'', ''disk'' or ''spheroid''')
    do k = n + 1, max_species
      if (len_trim(cfg%shape(k)) > 0) call input_error('suspension', 'shape('//int_text(k)//')', &
          ''''//trim(cfg%shape(k))//''' after an empty shape('//int_text(n + 1)//')', &
          'the species given in order, shape(1) to shape('//int_text(n)//') without gaps')
    end do
    do k = 1, n
      index = '('//int_text(k)//')'
      call require_option('suspension', 'shape'//index, cfg%shape(k), &
                          [character(len=8) :: 'sphere', 'needle', 'disk', 'spheroid'])
      call require_positive('suspension', 'radius'//index, cfg%radius(k))
      select case (trim(cfg%shape(k)))
      case ('needle', 'disk')
        if (.not. (cfg%aspect_ratio(k) >= 1.0_wp)) call input_error('suspension', 'aspect_ratio'//index, &
            real_text(cfg%aspect_ratio(k)), '>= 1 for '//trim(cfg%shape(k))//' (long over short semi-axis)')
      case ('spheroid')
        call require_positive('suspension', 'aspect_ratio'//index, cfg%aspect_ratio(k))
      end select
      if (cfg%count(k) < 0) call input_error('suspension', 'count'//index, int_text(cfg%count(k)), &
          '>= 1, or 0 with a volume_fraction'//index)
      if (.not. (cfg%volume_fraction(k) >= 0.0_wp .and. cfg%volume_fraction(k) < 0.74_wp)) call input_error( &
          'suspension', 'volume_fraction'//index, real_text(cfg%volume_fraction(k)), &
          '0 <= volume_fraction < 0.74 (0 with a count; 0.74 is the densest packing of spheres)')
      if ((cfg%count(k) > 0) .eqv. (cfg%volume_fraction(k) > 0.0_wp)) call input_error('suspension', &
          'count'//index, int_text(cfg%count(k))//' with volume_fraction'//index//' = '// &
          real_text(cfg%volume_fraction(k)), 'exactly one of count > 0 and volume_fraction > 0 per species')
    end do
    if (sum(cfg%volume_fraction(1:n)) >= 0.74_wp) call input_error('suspension', 'volume_fraction', &
        real_text(sum(cfg%volume_fraction(1:n)))//' in all', '< 0.74 in all (the densest packing of spheres)')
    call require_nonnegative('suspension', 'min_gap', cfg%min_gap)
    call require_nonnegative('suspension', 'velocity_rms', cfg%velocity_rms)
    if (cfg%max_attempts < 1) call input_error('suspension', 'max_attempts', int_text(cfg%max_attempts), &
        '>= 1 (random tries per body)')
    call require_nonnegative('suspension', 'memory_limit', cfg%memory_limit)
  end subroutine check_suspension_group

  subroutine write_suspension_group(unit, cfg)
    integer, intent(in) :: unit
    type(suspension_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=suspension)
  end subroutine write_suspension_group
end module config_suspension
