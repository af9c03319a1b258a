!> &scene fluid = 'stokes': each spheroid feels the drag and torque of its analytic resistance
!> tensors in quiescent fluid at its current velocities (module stokes_resistance; Happel & Brenner 1965),
!> without a grid. The provider of module particle_hydrodynamics for the fluid-free Stokes scenes.
module stokes_hydrodynamics
  use agglo_kinds, only: wp
  use spheroid, only: spheroid_t
  use particle_system, only: particle_system_t, particle_loads_t
  use stokes_resistance, only: stokes_resistance_t, stokes_resistance_of, stokes_loads
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  implicit none
  private
  public :: stokes_hydrodynamics_t, stokes_hydrodynamics_create

  type, extends(particle_hydrodynamics_t) :: stokes_hydrodynamics_t
    type(stokes_resistance_t), allocatable :: resistance(:)   !< (n) each body's tensors (body frame)
  contains
    procedure :: loads => stokes_body_loads
  end type stokes_hydrodynamics_t

contains

  !> The resistances of the system's bodies in a fluid of dynamic viscosity mu (Pa s).
  subroutine stokes_hydrodynamics_create(provider, system, dynamic_viscosity)
    type(stokes_hydrodynamics_t), intent(out) :: provider
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dynamic_viscosity
    integer :: i
    allocate(provider%resistance(system%n))
    do i = 1, system%n
      provider%resistance(i) = stokes_resistance_of(system%shapes(i), dynamic_viscosity)
    end do
  end subroutine stokes_hydrodynamics_create

  !> Drag and torque of each body at its current velocities (lab frame); theta plays no part (no
  !> fluid step).
  subroutine stokes_body_loads(self, system, theta, loads)
    class(stokes_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
    integer :: i
    do i = 1, system%n
      call stokes_loads(self%resistance(i), system%bodies(i), loads%force(:, i), loads%torque(:, i))
    end do
  end subroutine stokes_body_loads
end module stokes_hydrodynamics
