!> Namelist group &dlvo: DLVO interaction between the particles (Eq. 13 of the paper with the
!> curvature factor of Eq. 14). Defaults are the paper's Table 1 (calcite in water at 293 K).
module config_dlvo
  use agglo_kinds, only: wp
  use deck_file, only: deck_t, check_namelist_read, require_positive, require_nonnegative, require_range, &
                       require_option, require_positive_int
  implicit none
  private
  public :: dlvo_config_t, read_dlvo_group, check_dlvo_group, write_dlvo_group

  type :: dlvo_config_t
    real(wp) :: hamaker = 22.3e-21_wp               !< J, Hamaker constant A (Table 1: 22.3 zJ)
    real(wp) :: debye_kappa = 328947368.0_wp        !< 1/m, inverse Debye length kappa (Table 1)
    character(len=16) :: surface_potential_from = 'charge_density'  !< 'charge_density' | 'theta'
    real(wp) :: surface_charge_density = 3.7e-4_wp  !< C/m^2, converted to Theta by Grahame's equation
    real(wp) :: theta = 0.0_wp                      !< reduced surface potential tanh(z e psi0/4kT), if 'theta'
    real(wp) :: temperature = 293.0_wp              !< K (Table 2)
    real(wp) :: relative_permittivity = 80.1_wp     !< water at 20 C (CRC Handbook)
    integer :: valence = 1                          !< z of the symmetric z:z electrolyte
    real(wp) :: vdw_cutoff = 5.0e-9_wp              !< m, vdW term uses max(h, vdw_cutoff) (paper, sec. 2.2.3)
    character(len=16) :: curvature_factor = 'eq14'  !< 'eq14' (paper) | 'derjaguin' (exact) | 'none' (= 1)
  end type dlvo_config_t

  real(wp) :: hamaker, debye_kappa, surface_charge_density, theta, temperature, relative_permittivity, vdw_cutoff
  character(len=16) :: surface_potential_from, curvature_factor
  integer :: valence
  namelist /dlvo/ hamaker, debye_kappa, surface_potential_from, surface_charge_density, theta, temperature, &
                  relative_permittivity, valence, vdw_cutoff, curvature_factor

contains

  subroutine to_namelist(cfg)
    type(dlvo_config_t), intent(in) :: cfg
    hamaker = cfg%hamaker; debye_kappa = cfg%debye_kappa; surface_potential_from = cfg%surface_potential_from
    surface_charge_density = cfg%surface_charge_density; theta = cfg%theta; temperature = cfg%temperature
    relative_permittivity = cfg%relative_permittivity; valence = cfg%valence; vdw_cutoff = cfg%vdw_cutoff
    curvature_factor = cfg%curvature_factor
  end subroutine to_namelist

  subroutine from_namelist(cfg)
    type(dlvo_config_t), intent(inout) :: cfg
    cfg%hamaker = hamaker; cfg%debye_kappa = debye_kappa; cfg%surface_potential_from = surface_potential_from
    cfg%surface_charge_density = surface_charge_density; cfg%theta = theta; cfg%temperature = temperature
    cfg%relative_permittivity = relative_permittivity; cfg%valence = valence; cfg%vdw_cutoff = vdw_cutoff
    cfg%curvature_factor = curvature_factor
  end subroutine from_namelist

  subroutine read_dlvo_group(deck, cfg)
    type(deck_t), intent(in) :: deck
    type(dlvo_config_t), intent(out) :: cfg
    integer :: ios
    character(len=512) :: message
    call to_namelist(cfg)
    read(deck%lines, nml=dlvo, iostat=ios, iomsg=message)
    call check_namelist_read(deck, 'dlvo', ios, message)
    call from_namelist(cfg)
  end subroutine read_dlvo_group

  !> Hamaker = 0 switches the vdW term off (allowed); a negative one would make vdW repulsive.
  subroutine check_dlvo_group(cfg)
    type(dlvo_config_t), intent(in) :: cfg
    call require_nonnegative('dlvo', 'hamaker', cfg%hamaker)
    call require_positive('dlvo', 'debye_kappa', cfg%debye_kappa)
    call require_option('dlvo', 'surface_potential_from', cfg%surface_potential_from, &
                        [character(len=16) :: 'charge_density', 'theta'])
    ! Theta = tanh(z e psi0 / 4 k_B T) lies in (-1, 1); only Theta^2 enters Eq. 13.
    if (cfg%surface_potential_from == 'theta') call require_range('dlvo', 'theta', cfg%theta, -1.0_wp, 1.0_wp)
    if (cfg%surface_potential_from == 'charge_density') &
        call require_range('dlvo', 'surface_charge_density', cfg%surface_charge_density, -10.0_wp, 10.0_wp)
    call require_positive('dlvo', 'temperature', cfg%temperature)
    call require_range('dlvo', 'relative_permittivity', cfg%relative_permittivity, 1.0_wp, 1.0e4_wp)
    call require_positive_int('dlvo', 'valence', cfg%valence)
    call require_positive('dlvo', 'vdw_cutoff', cfg%vdw_cutoff)
    call require_option('dlvo', 'curvature_factor', cfg%curvature_factor, &
                        [character(len=16) :: 'eq14', 'derjaguin', 'none'])
  end subroutine check_dlvo_group

  subroutine write_dlvo_group(unit, cfg)
    integer, intent(in) :: unit
    type(dlvo_config_t), intent(in) :: cfg
    call to_namelist(cfg)
    write(unit, nml=dlvo)
  end subroutine write_dlvo_group
end module config_dlvo
