!> &scene particle_coupling = 'point': the hydrodynamic-load provider of the bodies in the resolved
!> fluid as point particles (module particle_hydrodynamics; the physics in coupling/point_particle_coupling).
!> The fluid step is the particle-free one (forced_fluid_advance: the same fused step as the
!> resolved scene without bodies); the fluid is sampled at the bodies' centres before and after it,
!> and the sub-steps read it interpolated linearly in time between u^n and u^n+1.
module point_hydrodynamics
  use agglo_kinds, only: wp, i8
  use fluid_solver, only: fluid_solver_t
  use forcing_driver, only: forcing_driver_t, forced_fluid_advance
  use particle_system, only: particle_system_t, particle_loads_t, wrap_body
  use point_particle_coupling, only: point_coupling_t, point_fluid_t, point_coupling_create, point_coupling_sample, &
                                     point_fluid_at, point_body_loads, sample_start, sample_end, point_free_step
  use particle_hydrodynamics, only: particle_hydrodynamics_t
  use rigid_body, only: added_inertia_t
  use timer_registry, only: timer_tic, timer_toc
  use shared_work, only: rank_block, share_columns
  implicit none
  private
  public :: point_hydrodynamics_t, point_hydrodynamics_create

  type, extends(particle_hydrodynamics_t) :: point_hydrodynamics_t
    type(point_coupling_t) :: coupling
  contains
    procedure :: prepare => point_prepare
    procedure :: fluid_step => point_fluid_step
    procedure :: loads => point_loads
    procedure :: impulse_inertia => point_impulse_inertia
    procedure :: member_loads => point_member_loads
    procedure :: single_step => point_single_step
    procedure :: centre_fluid_velocity => point_centre_fluid_velocity
  end type point_hydrodynamics_t

contains

  !> The provider for the system's bodies in the solver's fluid; added_mass: the implicit
  !> added-mass term (&scene added_mass).
  subroutine point_hydrodynamics_create(provider, solver, system, added_mass)
    type(point_hydrodynamics_t), intent(out) :: provider
    type(fluid_solver_t), intent(in) :: solver
    type(particle_system_t), intent(in) :: system
    logical, intent(in) :: added_mass
    call point_coupling_create(provider%coupling, system%shapes, solver%density, solver%density * solver%viscosity, &
                               [solver%grid%lx, solver%grid%ly, solver%grid%lz], added_mass)
  end subroutine point_hydrodynamics_create

  !> The fluid at the current centres, frozen until the first fluid step.
  subroutine point_prepare(self, solver, system)
    class(point_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver
    type(particle_system_t), intent(in) :: system
    call point_coupling_sample(self%coupling, solver%grid, solver%u, solver%v, solver%w, system%bodies, sample_start)
  end subroutine point_prepare

  subroutine point_fluid_step(self, solver, forcing, system, dt)
    class(point_hydrodynamics_t), intent(inout) :: self
    type(fluid_solver_t), intent(inout) :: solver
    type(forcing_driver_t), intent(inout) :: forcing
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: dt
    call timer_tic('point sampling')
    call point_coupling_sample(self%coupling, solver%grid, solver%u, solver%v, solver%w, system%bodies, sample_start)
    call timer_toc('point sampling')
    call forced_fluid_advance(forcing, solver, dt)
    call timer_tic('point sampling')
    call point_coupling_sample(self%coupling, solver%grid, solver%u, solver%v, solver%w, system%bodies, sample_end, dt)
    call timer_toc('point sampling')
  end subroutine point_fluid_step

  subroutine point_loads(self, system, theta, loads)
    class(point_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    type(particle_loads_t), intent(inout) :: loads
    type(point_fluid_t) :: fluid
    integer :: i
    do i = 1, system%n
      fluid = point_fluid_at(self%coupling, i, system%bodies(i)%position, theta)
      call point_body_loads(self%coupling, i, system%bodies(i), fluid, system%dlvo_loads%force(:, i), &
                            loads%force(:, i), loads%torque(:, i))
    end do
  end subroutine point_loads

  !> With the implicit added mass the loads move each body with m + rho_f V K (no rotational added
  !> inertia in the point model).
  function point_impulse_inertia(self, system) result(added)
    class(point_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    type(added_inertia_t), allocatable :: added(:)
    integer :: i
    allocate(added(system%n))
    if (.not. self%coupling%with_added_mass) return
    do i = 1, system%n
      added(i)%mass = self%coupling%added_mass(:, i)
    end do
  end function point_impulse_inertia

  !> point_loads for the members only (the others' loads are not touched).
  subroutine point_member_loads(self, system, theta, members, loads)
    class(point_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(in) :: system
    real(wp), intent(in) :: theta
    integer, intent(in) :: members(:)
    type(particle_loads_t), intent(inout) :: loads
    type(point_fluid_t) :: fluid
    integer :: i, k
    do k = 1, size(members)
      i = members(k)
      fluid = point_fluid_at(self%coupling, i, system%bodies(i)%position, theta)
      call point_body_loads(self%coupling, i, system%bodies(i), fluid, system%dlvo_loads%force(:, i), &
                            loads%force(:, i), loads%torque(:, i))
    end do
  end subroutine point_member_loads

  !> The listed bodies over the whole last fluid step dt in one exact exponential update
  !> (point_free_step), positions wrapped into the box. Each rank updates its block of the list
  !> (shared_work) and the new states are gathered: every rank holds what one rank would compute.
  subroutine point_single_step(self, system, bodies, dt)
    class(point_hydrodynamics_t), intent(in) :: self
    type(particle_system_t), intent(inout) :: system
    integer, intent(in) :: bodies(:)
    real(wp), intent(in) :: dt
    integer, parameter :: state_size = 16
    real(wp), allocatable :: states(:, :)
    integer :: k, i, first, last
    call rank_block(size(bodies), first, last)
    allocate(states(state_size, size(bodies)))
    do k = first, last
      i = bodies(k)
      call point_free_step(self%coupling, i, system%bodies(i), dt)
      call wrap_body(system, i)
      ! The wrap counts are small integers, exact in real(wp).
      states(:, k) = [system%bodies(i)%position, system%bodies(i)%velocity, system%bodies(i)%quaternion, &
                      system%bodies(i)%angular_velocity_body, real(system%wraps(:, i), wp)]
    end do
    call share_columns(states)
    do k = 1, size(bodies)
      if (k >= first .and. k <= last) cycle
      i = bodies(k)
      system%bodies(i)%position = states(1:3, k)
      system%bodies(i)%velocity = states(4:6, k)
      system%bodies(i)%quaternion = states(7:10, k)
      system%bodies(i)%angular_velocity_body = states(11:13, k)
      system%wraps(:, i) = nint(states(14:16, k), i8)
    end do
  end subroutine point_single_step

  function point_centre_fluid_velocity(self, which) result(velocity)
    class(point_hydrodynamics_t), intent(in) :: self
    integer, intent(in) :: which
    real(wp), allocatable :: velocity(:,:)
    velocity = self%coupling%velocity(:, :, which)
  end function point_centre_fluid_velocity
end module point_hydrodynamics
