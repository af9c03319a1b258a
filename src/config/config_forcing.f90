!> Namelist group &forcing: Eswaran & Pope (1988) stochastic forcing of the resolved box
!> (docs/physics.md section 3; paper section 2.1, Eqs. 2-6). SI units throughout.
!>
!> The strength is set in exactly one of three ways (the other two stay unset):
!>   sigma              m/s^2   standard deviation of the real and of the imaginary part of each
!>                              component of the Ornstein-Uhlenbeck coefficients b^ (paper Eq. 3)
!>   epsilon_star       m^2/s^3 epsilon* = sigma^2 T_L (paper, after Eq. 3), dimensional here
!>   target_dissipation m^2/s^3 the energy input wanted; epsilon* follows from the finite-T_L
!>                              estimate of Eswaran & Pope (docs/physics.md section 3), which needs the
!>                              box, so the conversion happens when the forcing is set up.
module config_forcing
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_nonnegative, require_option, &
                       real_text, int_text
  use error_handling, only: input_error
  implicit none
  private
  public :: forcing_config_t, read_forcing_group, check_forcing_group, write_forcing_group, &
            forcing_unset, forcing_is_set, forcing_strength_input, forcing_mode_extent, cutoff_slack

  !> Marks a strength input the deck did not give (a value nobody types; it survives a round trip
  !> through the resolved deck run.nml, so that deck reads back to the same configuration).
  real(wp), parameter :: forcing_unset = -huge(1.0_wp)

  !> Relative slack on |k| <= kappa_F so that a cut-off typed as e.g. sqrt(5) = 2.2360679775
  !> still includes the |n|^2 = 5 shell despite decimal rounding.
  real(wp), parameter :: cutoff_slack = 1.0e-10_wp

  type :: forcing_config_t
    real(wp) :: time_scale = 0.01_wp                 !< s, T_L of the Ornstein-Uhlenbeck processes
    real(wp) :: sigma = forcing_unset                !< m/s^2, OU standard deviation (one of three)
    real(wp) :: epsilon_star = forcing_unset         !< m^2/s^3, sigma^2 T_L (one of three)
    real(wp) :: target_dissipation = forcing_unset   !< m^2/s^3, E&P estimate sets epsilon* (one of three)
    real(wp) :: kappa_f_ratio = 2.3_wp              !< cut-off kappa_F in units of kappa0 = 2 pi / L (paper: 2.3)
    character(len=16) :: update = 'exact'            !< 'exact' OU update | 'euler_maruyama' (paper Eq. 3)
    integer :: statistics_interval = 100             !< steps between flow-statistics rows (flow_statistics.h5); 0 = none
    real(wp) :: average_start = 0.0_wp               !< s, time averages of the flow statistics start here
    !> OU coefficients at the start of a fresh run: 'field' = those stored with the initial field
    !> (forcing/state of &fluid init_file, when init = 'file'; else as 'stationary') | 'stationary' =
    !> drawn from N(0, sigma^2), uncorrelated with the velocity (docs/theory.md, forcing start).
    character(len=16) :: initial_state = 'field'
  end type forcing_config_t

  real(wp) :: time_scale, sigma, epsilon_star, target_dissipation, kappa_f_ratio, average_start
  character(len=16) :: update, initial_state
  integer :: statistics_interval
  namelist /forcing/ time_scale, sigma, epsilon_star, target_dissipation, kappa_f_ratio, update, &
                     statistics_interval, average_start, initial_state

contains

  subroutine to_namelist(cfg)
    type(forcing_config_t), intent(in) :: cfg
    time_scale = cfg%time_scale; sigma = cfg%sigma; epsilon_star = cfg%epsilon_star
    target_dissipation = cfg%target_dissipation; kappa_f_ratio = cfg%kappa_f_ratio; update = cfg%update
    statistics_interval = cfg%statistics_interval; average_start = cfg%average_start
    initial_state = cfg%initial_state
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(forcing_config_t), intent(inout) :: cfg
    cfg%time_scale = time_scale; cfg%sigma = sigma; cfg%epsilon_star = epsilon_star
    cfg%target_dissipation = target_dissipation; cfg%kappa_f_ratio = kappa_f_ratio; cfg%update = update
    cfg%statistics_interval = statistics_interval; cfg%average_start = average_start
    cfg%initial_state = initial_state
  end subroutine from_namelist

  subroutine read_forcing_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(forcing_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=forcing, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'forcing', ios, message)
    call from_namelist(cfg)
  end subroutine read_forcing_group

  !> Largest |n_d| of a forced mode along each axis: k_d = 2 pi n_d / L_d <= kappa_F = ratio 2 pi / L_max.
  pure function forcing_mode_extent(kappa_f_ratio, lengths) result(extent)
    real(wp), intent(in) :: kappa_f_ratio, lengths(3)
    integer :: extent(3)
    extent = floor(kappa_f_ratio * (lengths / maxval(lengths)) * (1.0_wp + cutoff_slack))
  end function forcing_mode_extent

  pure logical function forcing_is_set(value)
    real(wp), intent(in) :: value
    forcing_is_set = (value /= forcing_unset)
  end function forcing_is_set

  !> Name of the one strength input the deck gave ('sigma' | 'epsilon_star' | 'target_dissipation'),
  !> '' if none, 'several' if more than one.
  function forcing_strength_input(cfg) result(name)
    type(forcing_config_t), intent(in) :: cfg
    character(len=:), allocatable :: name
    integer :: given
    given = count([forcing_is_set(cfg%sigma), forcing_is_set(cfg%epsilon_star), &
                   forcing_is_set(cfg%target_dissipation)])
    if (given == 0) then
      name = ''
    else if (given > 1) then
      name = 'several'
    else if (forcing_is_set(cfg%sigma)) then
      name = 'sigma'
    else if (forcing_is_set(cfg%epsilon_star)) then
      name = 'epsilon_star'
    else
      name = 'target_dissipation'
    end if
  end function forcing_strength_input

  subroutine check_forcing_group(cfg)
    type(forcing_config_t), intent(in) :: cfg
    character(len=:), allocatable :: given
    call require_positive('forcing', 'time_scale', cfg%time_scale)
    ! kappa_F below kappa0 would force no wavevector at all (the smallest nonzero |k| is kappa0).
    if (.not. (cfg%kappa_f_ratio >= 1.0_wp)) call input_error('forcing', 'kappa_f_ratio', &
        real_text(cfg%kappa_f_ratio), '>= 1 (kappa_F in units of kappa0 = 2 pi / L; below kappa0 no '// &
        'wavevector is forced; the paper uses 2.3)')
    call require_option('forcing', 'update', cfg%update, [character(len=16) :: 'exact', 'euler_maruyama'])
    call require_option('forcing', 'initial_state', cfg%initial_state, [character(len=16) :: 'field', 'stationary'])
    if (cfg%statistics_interval < 0) call input_error('forcing', 'statistics_interval', &
        int_text(cfg%statistics_interval), '>= 0 (steps between flow-statistics rows; 0 = none)')
    call require_nonnegative('forcing', 'average_start', cfg%average_start)
    given = forcing_strength_input(cfg)
    if (given == '') call input_error('forcing', 'sigma / epsilon_star / target_dissipation', 'none given', &
        'exactly one of them (the forcing strength)')
    if (given == 'several') call input_error('forcing', 'sigma / epsilon_star / target_dissipation', &
        'more than one given ('//given_list(cfg)//')', 'exactly one of them (the forcing strength)')
    ! The OU variance sigma^2 = epsilon*/T_L must be positive: a negative sigma, epsilon* or
    ! dissipation is a negative (or meaningless) variance; zero forcing is scene forcing = 'none'.
    if (forcing_is_set(cfg%sigma)) call require_positive_strength('sigma', cfg%sigma, 'm/s^2')
    if (forcing_is_set(cfg%epsilon_star)) call require_positive_strength('epsilon_star', cfg%epsilon_star, &
        'm^2/s^3 (= sigma^2 T_L; a negative value is a negative OU variance)')
    if (forcing_is_set(cfg%target_dissipation)) call require_positive_strength('target_dissipation', &
        cfg%target_dissipation, 'm^2/s^3')
  end subroutine check_forcing_group

  subroutine require_positive_strength(variable, value, unit_note)
    character(len=*), intent(in) :: variable, unit_note
    real(wp), intent(in) :: value
    if (.not. (value > 0.0_wp)) call input_error('forcing', variable, real_text(value), &
        '> 0, '//unit_note//'; for no forcing set &scene forcing = ''none''')
  end subroutine require_positive_strength

  function given_list(cfg) result(text)
    type(forcing_config_t), intent(in) :: cfg
    character(len=:), allocatable :: text
    text = ''
    if (forcing_is_set(cfg%sigma)) text = text//' sigma'
    if (forcing_is_set(cfg%epsilon_star)) text = text//' epsilon_star'
    if (forcing_is_set(cfg%target_dissipation)) text = text//' target_dissipation'
    text = trim(adjustl(text))
  end function given_list

  subroutine write_forcing_group(unit, cfg)
    integer, intent(in) :: unit
    type(forcing_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=forcing)
  end subroutine write_forcing_group
end module config_forcing
