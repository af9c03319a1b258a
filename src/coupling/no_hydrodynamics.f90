!> &scene fluid = 'none' with particles, or a resolved fluid without particles: the provider of no
!> hydrodynamic load (module particle_hydrodynamics). In a resolved fluid its fluid step is the
!> fluid alone, the fused particle-free step (the provider's default, forced_fluid_advance).
module no_hydrodynamics
  use agglo_kinds, only: wp
  use particle_system, only: particle_system_t, particle_loads_t
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  implicit none
  private
  public :: no_hydrodynamics_t

  type, extends(particle_hydrodynamics_t) :: no_hydrodynamics_t
  contains
    procedure :: loads => no_loads
  end type no_hydrodynamics_t

contains

  subroutine no_loads(self, system, theta, loads)
    class(no_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
    loads%force = 0.0_wp
    loads%torque = 0.0_wp
  end subroutine no_loads
end module no_hydrodynamics
