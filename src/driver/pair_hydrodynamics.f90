!> The part of the resolved pair scene (module resolved_pair_scene) that changes with
!> &scene particle_coupling: how the fluid step sees the bodies and which hydrodynamic loads the
!> particle sub-steps feel. 'point' (module point_hydrodynamics): the fluid is solved without the
!> bodies and each body feels its analytic Stokes resistance in the flow at its centre;
!> 'resolved' (module resolved_hydrodynamics): the fluid step imposes the bodies with the immersed
!> boundary and integrates their loads.
!>
!> One fluid step of the scene: fluid_step(dt) advances the fluid from t^n to t^n+1 = t^n + dt
!> (with the Eswaran-Pope forcing, if on), then the particles take &scene particle_substeps steps
!> of dt / particle_substeps, each under loads(theta) of its current state, theta = (t - t^n) / dt.
!> What a provider keeps across fluid steps beyond the fluid and the particle system goes into the
!> checkpoint through write_checkpoint / read_checkpoint, so a checkpoint at a fluid-step boundary
!> restarts it bit for bit.
module pair_hydrodynamics
  use agglo_kinds, only: wp
  use fluid_solver, only: fluid_solver_t
  use forcing_driver, only: forcing_driver_t
  use particle_system, only: particle_system_t, particle_loads_t
  use rigid_body, only: added_inertia_t
  use checkpoint_files, only: checkpoint_t
  implicit none
  private
  public :: pair_hydrodynamics_t

  type, abstract :: pair_hydrodynamics_t
  contains
    !> Ready for the loads of the system's current state before any fluid step (a start or a
    !> restart; collective).
    procedure(prepare_interface), deferred :: prepare
    !> Advance the fluid by dt with the bodies as this coupling sees them (collective).
    procedure(fluid_step_interface), deferred :: fluid_step
    !> Hydrodynamic force and torque on every body of the system's current state at the fraction
    !> theta in [0, 1] of the last fluid step (the same on every rank; not collective).
    procedure(loads_interface), deferred :: loads
    !> The provider's own state across fluid steps into / out of a checkpoint transaction (none by
    !> default; the resolved provider keeps its lagged loads and imposed velocities).
    procedure :: write_checkpoint => no_checkpoint_write
    procedure :: read_checkpoint => no_checkpoint_read
    !> A line for the progress log about the last fluid step's coupling ('' when there is nothing).
    procedure :: progress_text => no_progress_text
    !> The added masses (body frame) with which the loads move each of the system's bodies beyond
    !> its own mass: the ones its contact impulses must carry too (module rigid_body, "Impulses in a
    !> fluid"; none by default: loads that divide by the body's mass alone).
    procedure :: impulse_inertia => no_impulse_inertia
  end type pair_hydrodynamics_t

  abstract interface
    subroutine prepare_interface(self, solver, system)
      import :: pair_hydrodynamics_t, fluid_solver_t, particle_system_t
      class(pair_hydrodynamics_t), intent(inout) :: self
      type(fluid_solver_t), intent(inout) :: solver   ! a start may set the fluid inside the bodies
      type(particle_system_t), intent(in) :: system
    end subroutine prepare_interface

    subroutine fluid_step_interface(self, solver, forcing, system, dt)
      import :: pair_hydrodynamics_t, fluid_solver_t, forcing_driver_t, particle_system_t, wp
      class(pair_hydrodynamics_t), intent(inout) :: self
      type(fluid_solver_t), intent(inout) :: solver
      type(forcing_driver_t), intent(inout) :: forcing
      type(particle_system_t), intent(in) :: system
      real(wp), intent(in) :: dt
    end subroutine fluid_step_interface

    subroutine loads_interface(self, system, theta, loads)
      import :: pair_hydrodynamics_t, particle_system_t, particle_loads_t, wp
      class(pair_hydrodynamics_t), intent(in) :: self
      type(particle_system_t), intent(in) :: system
      real(wp), intent(in) :: theta
      type(particle_loads_t), intent(inout) :: loads
    end subroutine loads_interface
  end interface

contains

  subroutine no_checkpoint_write(self, transaction)
    class(pair_hydrodynamics_t), intent(in) :: self
    type(checkpoint_t), intent(in) :: transaction
  end subroutine no_checkpoint_write

  function no_progress_text(self) result(text)
    class(pair_hydrodynamics_t), intent(in) :: self
    character(len=:), allocatable :: text
    text = ''
  end function no_progress_text

  function no_impulse_inertia(self, system) result(added)
    class(pair_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    type(added_inertia_t), allocatable :: added(:)
    allocate(added(system%n))
  end function no_impulse_inertia

  subroutine no_checkpoint_read(self, restart)
    class(pair_hydrodynamics_t), intent(inout) :: self
    type(checkpoint_t), intent(in) :: restart
  end subroutine no_checkpoint_read
end module pair_hydrodynamics
