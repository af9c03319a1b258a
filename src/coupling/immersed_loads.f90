!> Force and torque on the immersed bodies by momentum balance (Mark & van Wachem 2008; docs/theory.md,
!> "Immersed boundary: imposition and loads").
!>
!> Each imposition changes the momentum on the grid by rho dV sum (u_imposed - u_before) e_c over the
!> ghost and interior nodes of the body (each component at its own nodes; account). Part of it goes
!> to the fictitious fluid on the body's own nodes; the rest is what the body gives the real fluid.
!> So the force on the body is
!>   F = -(1/dt) [sum over both impositions of rho dV sum (u_imposed - u_before) e_c]
!>       + (1/dt) rho dV sum_{nodes of the body at n+1} (u^{n+1} - u^n) e_c,
!> the second term the discrete rate of change of the fictitious fluid's momentum, rho_f d/dt(V U)
!> for a rigid body. Taken over the nodes the body holds at n+1, it also carries the momentum a
!> node brings when it is covered or leaves when it is uncovered, so a change of status adds no
!> spike u/dt to the force (docs/theory.md, "Immersed boundary: moving bodies"). The torque likewise
!> with r x, about each body's centre.
module immersed_loads
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM
  use agglo_kinds, only: wp
  use parallel_env, only: world, mpi_wp
  use fluid_grid, only: fluid_grid_t
  use immersed_boundary, only: immersed_boundary_t
  use immersed_diagnostics, only: record_load_jump
  implicit none
  private
  public :: ibm_begin_step, ibm_step_loads
  !> The load bookkeeping of one node, for the imposition and for a solver that imposes the body rows itself
  public :: account

contains

  !> Start a step's load bookkeeping (call after ibm_set_bodies has placed the bodies at t^{n+1},
  !> with u^n in u, v, w): the impositions of the step add to zeroed momentum changes, and the
  !> fictitious fluid's change starts from minus the momentum of u^n on the bodies' new nodes.
  subroutine ibm_begin_step(ibm, grid, u, v, w)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    ibm%momentum_change = 0
    ibm%angular_change = 0
    ibm%inertia_change = 0
    call add_body_momentum(ibm, grid, u, v, w, -1.0_wp)
  end subroutine ibm_begin_step

  !> Force (N) and torque (N m, about each centre) on every body over the step of length dt (call
  !> after the step's impositions, with u^{n+1} in u, v, w; collective): minus the momentum the
  !> impositions added per unit time, plus the rate of change of the fictitious fluid's momentum
  !> on the body's nodes (summed over the ranks).
  subroutine ibm_step_loads(ibm, grid, u, v, w, dt, force, torque)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: dt
    real(wp), intent(out) :: force(:, :), torque(:, :)
    real(wp), allocatable :: total(:, :)
    integer :: n
    call add_body_momentum(ibm, grid, u, v, w, 1.0_wp)
    n = size(ibm%bodies)
    allocate(total(12, n))
    total(1:3, :) = ibm%momentum_change
    total(4:6, :) = ibm%angular_change
    total(7:12, :) = ibm%inertia_change
    call MPI_Allreduce(MPI_IN_PLACE, total, 12 * n, mpi_wp, MPI_SUM, world)
    ibm%inertia_change = total(7:12, :)
    force = (-total(1:3, :) + total(7:9, :)) / dt
    torque = (-total(4:6, :) + total(10:12, :)) / dt
    call record_load_jump(ibm%changes, ibm%force_history, force)
  end subroutine ibm_step_loads

  !> inertia_change += sign rho dV sum (u e_c and r x u e_c) over every body's ghost and interior nodes.
  subroutine add_body_momentum(ibm, grid, u, v, w, sign)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: sign
    call add_component(1, u)
    call add_component(2, v)
    call add_component(3, w)
  contains
    subroutine add_component(c, field)
      integer, intent(in) :: c
      real(wp), intent(in) :: field(0:, 0:, 0:)
      real(wp) :: factor
      integer :: m, n
      factor = sign * ibm%settings%fluid_density * grid%cell_volume
      associate (nodes => ibm%geometry%component(c), arms => ibm%arms(c))
        do m = 1, nodes%n_interior
          n = nodes%interior_body(m)
          call add_along_axis(ibm%inertia_change(1:3, n), ibm%inertia_change(4:6, n), c, arms%interior(:, m), &
                              factor * field(nodes%interior(1, m), nodes%interior(2, m), nodes%interior(3, m)))
        end do
        do m = 1, nodes%n_ghost
          n = nodes%ghost(m)%body
          call add_along_axis(ibm%inertia_change(1:3, n), ibm%inertia_change(4:6, n), c, arms%ghost(:, m), &
                              factor * field(nodes%ghost(m)%node(1), nodes%ghost(m)%node(2), nodes%ghost(m)%node(3)))
        end do
      end associate
    end subroutine add_component
  end subroutine add_body_momentum

  !> Momentum rho dV delta e_c and angular momentum rho dV r x (delta e_c) added at the node of
  !> lever arm r.
  subroutine account(ibm, grid, n, component, r, delta)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: n, component
    real(wp), intent(in) :: r(3), delta
    call add_along_axis(ibm%momentum_change(:, n), ibm%angular_change(:, n), component, r, &
                        ibm%settings%fluid_density * grid%cell_volume * delta)
  end subroutine account

  !> momentum += p e_c and angular += r x (p e_c), written out for the one nonzero component of
  !> p e_c (the terms of the cross product with a zero factor add nothing). The two products are
  !> rounded before they are added (volatile: not fused into the sums), as when the cross product
  !> was a separate function, so the loads are the same to the bit.
  subroutine add_along_axis(momentum, angular, component, r, p)
    real(wp), intent(inout) :: momentum(3), angular(3)
    integer, intent(in) :: component
    real(wp), intent(in) :: r(3), p
    real(wp), volatile :: moment_1, moment_2
    momentum(component) = momentum(component) + p
    select case (component)
    case (1)   ! r x (p, 0, 0) = (0, r3 p, -r2 p)
      moment_1 = r(3) * p
      moment_2 = r(2) * p
      angular(2) = angular(2) + moment_1
      angular(3) = angular(3) - moment_2
    case (2)   ! r x (0, p, 0) = (-r3 p, 0, r1 p)
      moment_1 = r(3) * p
      moment_2 = r(1) * p
      angular(1) = angular(1) - moment_1
      angular(3) = angular(3) + moment_2
    case default   ! r x (0, 0, p) = (r2 p, -r1 p, 0)
      moment_1 = r(2) * p
      moment_2 = r(1) * p
      angular(1) = angular(1) + moment_1
      angular(2) = angular(2) - moment_2
    end select
  end subroutine add_along_axis
end module immersed_loads
