!> The particles' hydrodynamics: what the scene loop (module scene_loop) asks of the bodies' coupling
!> to the fluid, one abstract provider selected once at set-up from the deck (module scene_setup):
!>   'none'       no hydrodynamic load (particles in vacuum; in a resolved fluid, the fluid alone:
!>                the fused particle-free step, module no_hydrodynamics),
!>   'stokes'     the analytic Stokes resistance of each spheroid in quiescent fluid, no grid
!>                (module stokes_hydrodynamics),
!>   'point'      point particles in the resolved fluid: the fluid solved without the bodies, each
!>                body under its Stokes resistance in the flow at its centre (module point_hydrodynamics),
!>   'resolved'   free bodies resolved by the immersed boundary (module resolved_hydrodynamics),
!>   'prescribed' bodies whose motion the deck prescribes, resolved by the immersed boundary
!>                (module prescribed_hydrodynamics; kinematic: not in the particle system).
!>
!> One fluid step of the loop: fluid_step(dt) advances the fluid from t^n to t^n+1 = t^n + dt with
!> the bodies as the coupling sees them (forcing -> predict -> couple -> project -> loads), then the
!> particles take &scene particle_substeps steps of dt / particle_substeps, each under loads(theta)
!> of its current state, theta = (t - t^n) / dt. What a provider keeps across fluid steps beyond the
!> fluid and the particle system goes into the checkpoint through write_checkpoint / read_checkpoint,
!> so a checkpoint at a fluid-step boundary restarts it bit for bit. The fluid-free scenes ('none',
!> 'stokes' without a grid) call loads only.
module particle_hydrodynamics
  use agglo_kinds, only: wp, i8
  use fluid_solver, only: fluid_solver_t
  use forcing_driver, only: forcing_driver_t, forced_fluid_advance
  use particle_system, only: particle_system_t, particle_loads_t
  use error_handling, only: fatal
  use rigid_body, only: added_inertia_t
  use checkpoint_files, only: checkpoint_t
  use body_surface_output, only: body_pose_t, system_body_poses
  implicit none
  private
  public :: particle_hydrodynamics_t

  type, abstract :: particle_hydrodynamics_t
  contains
    !> Hydrodynamic force and torque on every body of the system's current state at the fraction
    !> theta in [0, 1] of the last fluid step (the same on every rank; not collective).
    procedure(loads_interface), deferred :: loads
    !> Ready for the loads of the system's current state before any fluid step (a start or a
    !> restart; collective). Nothing by default.
    procedure :: prepare => no_prepare
    !> Advance the fluid by dt with the bodies as this coupling sees them (collective). By default
    !> the fluid without bodies: the fused particle-free step with the forcing (forced_fluid_advance).
    procedure :: fluid_step => fluid_alone_step
    !> Open the provider's time series in the run directory (append: a restart continuing them after
    !> the checkpoint's step last_step; collective). None by default.
    procedure :: open_outputs => no_outputs
    !> The provider's per-fluid-step outputs after fluid_step (bodies_loads.dat; collective). None by default.
    procedure :: record_fluid_step => no_record
    !> The provider's own state across fluid steps into / out of a checkpoint transaction (none by
    !> default; the resolved provider keeps its lagged loads and imposed velocities).
    procedure :: write_checkpoint => no_checkpoint_write
    procedure :: read_checkpoint => no_checkpoint_read
    !> Lines for the progress log about the last fluid step's coupling (none by default).
    procedure :: log_progress => no_progress
    !> The added masses (body frame) with which the loads move each of the system's bodies beyond
    !> its own mass: the ones its contact impulses must carry too (module rigid_body, "Impulses in a
    !> fluid"; none by default: loads that divide by the body's mass alone).
    procedure :: impulse_inertia => no_impulse_inertia
    !> The bodies' poses at the fluid's time for the field snapshots (not allocated: no bodies).
    !> By default the particle system's bodies.
    procedure :: body_poses => system_poses
    !> Close the provider's outputs and log its summary at the end of a run (collective).
    procedure :: finish => no_finish
    !> &scene substep_bodies = 'near' (module near_bodies): the loads of the listed bodies only (by
    !> default every body's), the one-step update of the fluid step for bodies with no pair force,
    !> and the fluid velocity at the centres at the start and the end of the last fluid step (3, n).
    !> Only the point provider has the last two.
    procedure :: member_loads => every_body_loads
    procedure :: single_step => no_single_step
    procedure :: centre_fluid_velocity => no_centre_fluid_velocity
  end type particle_hydrodynamics_t

  abstract interface
    subroutine loads_interface(self, system, theta, loads)
      import :: particle_hydrodynamics_t, particle_system_t, particle_loads_t, wp
      class(particle_hydrodynamics_t), intent(in) :: self
      type(particle_system_t), intent(in) :: system
      real(wp), intent(in) :: theta
      type(particle_loads_t), intent(inout) :: loads
    end subroutine loads_interface
  end interface

contains

  subroutine no_prepare(self, solver, system)
    class(particle_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver   ! a start may set the fluid inside the bodies
    type(particle_system_t), intent(in) :: system
  end subroutine no_prepare

  subroutine fluid_alone_step(self, solver, forcing, system, dt)
    class(particle_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver
    type(forcing_driver_t), intent(inout) :: forcing
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dt
    call forced_fluid_advance(forcing, solver, dt)   ! fluid_advance with the body force f^n, then f^n+1
  end subroutine fluid_alone_step

  subroutine no_outputs(self, append, last_step)
    class(particle_hydrodynamics_t), intent(inout) :: self
    logical, intent(in) :: append
    integer(i8), intent(in) :: last_step
  end subroutine no_outputs

  subroutine no_record(self, solver)
    class(particle_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(in) :: solver
  end subroutine no_record

  subroutine no_checkpoint_write(self, transaction)
    class(particle_hydrodynamics_t), intent(inout) :: self
    type(checkpoint_t), intent(in) :: transaction
  end subroutine no_checkpoint_write

  subroutine no_checkpoint_read(self, restart)
    class(particle_hydrodynamics_t), intent(inout) :: self
    type(checkpoint_t), intent(in) :: restart
  end subroutine no_checkpoint_read

  subroutine no_progress(self, solver)
    class(particle_hydrodynamics_t), intent(in) :: self
    type(fluid_solver_t), intent(in) :: solver
  end subroutine no_progress

  function no_impulse_inertia(self, system) result(added)
    class(particle_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    type(added_inertia_t), allocatable :: added(:)
    allocate(added(system%n))
  end function no_impulse_inertia

  subroutine system_poses(self, solver, system, poses)
    class(particle_hydrodynamics_t), intent(in) :: self
    type(fluid_solver_t), intent(in) :: solver
    type(particle_system_t), intent(in) :: system
    type(body_pose_t), allocatable, intent(out) :: poses(:)
    if (system%n > 0) poses = system_body_poses(system)
  end subroutine system_poses

  subroutine no_finish(self, solver, steps)
    class(particle_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(in) :: solver
    integer(i8), intent(in) :: steps          !< fluid steps of this run segment
  end subroutine no_finish

  subroutine every_body_loads(self, system, theta, members, loads)
    class(particle_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    integer, intent(in) :: members(:)
    type(particle_loads_t), intent(inout) :: loads
    call self%loads(system, theta, loads)
  end subroutine every_body_loads

  subroutine no_single_step(self, system, bodies, dt)
    class(particle_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(inout) :: system
    integer, intent(in) :: bodies(:)
    real(wp), intent(in) :: dt
    call fatal('particle hydrodynamics: this coupling has no one-step update (&scene substep_bodies = ''near'')')
  end subroutine no_single_step

  function no_centre_fluid_velocity(self, which) result(velocity)
    class(particle_hydrodynamics_t), intent(in) :: self
    integer, intent(in) :: which
    real(wp), allocatable :: velocity(:,:)
    allocate(velocity(3, 0))
    call fatal('particle hydrodynamics: this coupling samples no fluid at the centres (&scene substep_bodies = ''near'')')
  end function no_centre_fluid_velocity
end module particle_hydrodynamics
