!> Namelist group &fluid: fluid properties, discretisation options and the initial field.
module config_fluid
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_nonnegative, require_option, require_range, &
                       int_text
  use error_handling, only: input_error
  use file_system, only: longest_path
  implicit none
  private
  public :: fluid_config_t, read_fluid_group, check_fluid_group, write_fluid_group

  type :: fluid_config_t
    real(wp) :: density = 997.0_wp                 !< kg/m^3, water at 20 C (paper, Table 2)
    real(wp) :: viscosity = 1.0e-6_wp              !< m^2/s, kinematic (paper, Table 2)
    character(len=16) :: viscous_scheme = 'explicit'  !< 'explicit' | 'crank_nicolson'
    character(len=16) :: init = 'rest'             !< 'rest' | 'taylor_green' | 'random' | 'file'
    character(len=longest_path + 1) :: init_file = ''   !< field file for init = 'file'
    real(wp) :: init_amplitude = 1.0e-3_wp         !< m/s, velocity scale of 'taylor_green' / rms of 'random'
    real(wp) :: init_peak_wavenumber = 2.0_wp      !< spectrum peak of 'random', in units of 2 pi / length_x
    character(len=16) :: fft_planning = 'estimate' !< 'estimate' (reproducible) | 'measure' (faster plans, not bit-reproducible)
    character(len=16) :: pressure_scheme = 'non_incremental'  !< 'non_incremental' | 'incremental' (fluid_solver)
    !> The Crank-Nicolson predictor with immersed bodies (hypre, immersed_predictor): the relative
    !> residual ||b - A u*|| / ||b|| it stops at, and the iterations before the run stops.
    real(wp) :: predictor_tolerance = 1.0e-8_wp
    integer :: predictor_max_iterations = 200
  end type fluid_config_t

  real(wp) :: density, viscosity, init_amplitude, init_peak_wavenumber, predictor_tolerance
  integer :: predictor_max_iterations
  character(len=16) :: viscous_scheme, init, fft_planning, pressure_scheme
  character(len=longest_path + 1) :: init_file
  namelist /fluid/ density, viscosity, viscous_scheme, init, init_file, init_amplitude, init_peak_wavenumber, &
                  fft_planning, pressure_scheme, predictor_tolerance, predictor_max_iterations

contains

  subroutine to_namelist(cfg)
    type(fluid_config_t), intent(in) :: cfg
    density = cfg%density; viscosity = cfg%viscosity; viscous_scheme = cfg%viscous_scheme
    init = cfg%init; init_file = cfg%init_file; init_amplitude = cfg%init_amplitude
    init_peak_wavenumber = cfg%init_peak_wavenumber; fft_planning = cfg%fft_planning
    pressure_scheme = cfg%pressure_scheme
    predictor_tolerance = cfg%predictor_tolerance; predictor_max_iterations = cfg%predictor_max_iterations
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(fluid_config_t), intent(inout) :: cfg
    cfg%density = density; cfg%viscosity = viscosity; cfg%viscous_scheme = viscous_scheme
    cfg%init = init; cfg%init_file = init_file; cfg%init_amplitude = init_amplitude
    cfg%init_peak_wavenumber = init_peak_wavenumber; cfg%fft_planning = fft_planning
    cfg%pressure_scheme = pressure_scheme
    cfg%predictor_tolerance = predictor_tolerance; cfg%predictor_max_iterations = predictor_max_iterations
  end subroutine from_namelist

  subroutine read_fluid_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(fluid_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=fluid, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'fluid', ios, message)
    call from_namelist(cfg)
  end subroutine read_fluid_group

  subroutine check_fluid_group(cfg)
    type(fluid_config_t), intent(in) :: cfg
    call require_positive('fluid', 'density', cfg%density)
    call require_positive('fluid', 'viscosity', cfg%viscosity)
    call require_option('fluid', 'viscous_scheme', cfg%viscous_scheme, [character(len=16) :: 'explicit', 'crank_nicolson'])
    call require_option('fluid', 'init', cfg%init, [character(len=16) :: 'rest', 'taylor_green', 'random', 'file'])
    call require_nonnegative('fluid', 'init_amplitude', cfg%init_amplitude)
    call require_positive('fluid', 'init_peak_wavenumber', cfg%init_peak_wavenumber)
    call require_option('fluid', 'fft_planning', cfg%fft_planning, [character(len=16) :: 'estimate', 'measure'])
    call require_option('fluid', 'pressure_scheme', cfg%pressure_scheme, &
                        [character(len=16) :: 'non_incremental', 'incremental'])
    call require_range('fluid', 'predictor_tolerance', cfg%predictor_tolerance, 1.0e-14_wp, 1.0e-2_wp)
    if (cfg%predictor_max_iterations < 1 .or. cfg%predictor_max_iterations > 10000) call input_error('fluid', &
        'predictor_max_iterations', int_text(cfg%predictor_max_iterations), '1 to 10000')
    if (cfg%init == 'file' .and. len_trim(cfg%init_file) == 0) call input_error('fluid', 'init_file', &
        '''''', 'the path of an Agglo field snapshot or checkpoint (needed by init = ''file'')')
  end subroutine check_fluid_group

  subroutine write_fluid_group(unit, cfg)
    integer, intent(in) :: unit
    type(fluid_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=fluid)
  end subroutine write_fluid_group
end module config_fluid
