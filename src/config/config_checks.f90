!> Checks that involve more than one namelist group (each group checks itself first).
!> One subroutine per room of the code, so each room owns its own rules.
module config_checks
  use agglo_kinds, only: wp
  use agglo_config, only: agglo_config_t
  use deck_file, only: int_text, real_text
  use error_handling, only: input_error, fatal
  implicit none
  private
  public :: check_cross_groups

contains

  subroutine check_cross_groups(cfg, nranks)
    type(agglo_config_t), intent(in) :: cfg
    integer, intent(in) :: nranks
    call check_scene_combinations(cfg)
    if (cfg%scene%fluid == 'resolved') call check_fluid_cross(cfg, nranks)
    if (cfg%scene%forcing /= 'none') call check_forcing_cross(cfg)
    if (cfg%scene%particles /= 'none') call check_particle_cross(cfg)
  end subroutine check_cross_groups

  subroutine check_scene_combinations(cfg)
    type(agglo_config_t), intent(in) :: cfg
    if (cfg%scene%fluid == 'resolved' .and. cfg%scene%particles /= 'none') call fatal( &
        'deck: &scene fluid = ''resolved'' with particles = '''//trim(cfg%scene%particles)// &
        ''' needs the immersed-boundary coupling, which this version does not have yet; '// &
        'use fluid = ''none'' or ''stokes'' for particle runs, or particles = ''none''')
    if (cfg%scene%fluid /= 'resolved' .and. cfg%scene%particles == 'none') call input_error('scene', &
        'particles', '''none'' with fluid = '''//trim(cfg%scene%fluid)//'''', &
        '''pair'' (a fluid-free or Stokes scene has nothing to compute without particles)')
  end subroutine check_scene_combinations

  !> Resolved fluid: the grid must split into equal slabs along z and y (pencil transposes of the FFT).
  subroutine check_fluid_cross(cfg, nranks)
    type(agglo_config_t), intent(in) :: cfg
    integer, intent(in) :: nranks
    if (mod(cfg%grid%nz, nranks) /= 0) call input_error('grid', 'nz', int_text(cfg%grid%nz), &
        'a multiple of the number of MPI ranks ('//int_text(nranks)//')')
    if (mod(cfg%grid%ny, nranks) /= 0) call input_error('grid', 'ny', int_text(cfg%grid%ny), &
        'a multiple of the number of MPI ranks ('//int_text(nranks)//')')
  end subroutine check_fluid_cross

  subroutine check_forcing_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    if (cfg%scene%fluid /= 'resolved') call input_error('scene', 'forcing', ''''//trim(cfg%scene%forcing)// &
        ''' with fluid = '''//trim(cfg%scene%fluid)//'''', '''none'' unless fluid = ''resolved''')
  end subroutine check_forcing_cross

  !> Particle models: the nanometre-scale lengths must be far below the particle size (the DLVO and
  !> collision models are surface-gap models in the Derjaguin limit, h << r).
  subroutine check_particle_cross(cfg)
    type(agglo_config_t), intent(in) :: cfg
    if (cfg%scene%dlvo) then
      if (.not. (cfg%dlvo%vdw_cutoff < 0.01_wp * cfg%pair%radius)) call input_error('dlvo', 'vdw_cutoff', &
          real_text(cfg%dlvo%vdw_cutoff), '< 0.01 * &pair radius = '//real_text(0.01_wp * cfg%pair%radius)//' m')
    end if
    if (cfg%scene%collisions) then
      if (.not. (cfg%collision%detection_floor < 0.01_wp * cfg%pair%radius)) call input_error('collision', &
          'detection_floor', real_text(cfg%collision%detection_floor), &
          '< 0.01 * &pair radius = '//real_text(0.01_wp * cfg%pair%radius)//' m')
    end if
  end subroutine check_particle_cross
end module config_checks
