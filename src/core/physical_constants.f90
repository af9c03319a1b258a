!> Mathematical and physical constants (SI, CODATA 2018 exact values where defined).
module physical_constants
  use agglo_kinds, only: wp
  implicit none
  private
  public :: pi, two_pi, boltzmann_constant, elementary_charge, vacuum_permittivity, avogadro_number

  real(wp), parameter :: pi = 3.141592653589793238462643383279502884_wp
  real(wp), parameter :: two_pi = 2.0_wp * pi
  real(wp), parameter :: boltzmann_constant = 1.380649e-23_wp      !< J/K, exact (SI 2019)
  real(wp), parameter :: elementary_charge = 1.602176634e-19_wp    !< C, exact (SI 2019)
  real(wp), parameter :: vacuum_permittivity = 8.8541878128e-12_wp !< F/m, CODATA 2018
  real(wp), parameter :: avogadro_number = 6.02214076e23_wp        !< 1/mol, exact (SI 2019)
end module physical_constants
