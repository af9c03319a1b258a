!> The immersed-boundary imposition on the staggered velocity components and the hydrodynamic loads
!> by momentum balance (docs/theory.md, "Immersed boundary: imposition and loads").
!>
!> For rigid bodies with a given velocity U and angular velocity Omega about the centre c, the rigid
!> velocity at a point x is u_rigid(x) = U + Omega x r, r = minimum image of x - c.
!> - Interior nodes (immersed_geometry) take u_rigid at the node.
!> - Ghost node G, surface point B, image point M = B + d_M n, kappa = d_G/d_M: the ghost row
!>     (1 + kappa w_G) u_G = (1 + kappa) u_B - kappa sum_{j /= G} w_j u_j,   u_B = u_rigid(B)
!>   (the paper's Eq. 7, u_G = 2 u_IB - u_E, for the pure mirror kappa = 1; Mark & van Wachem 2008,
!>   anderson2025-methods Eq. 7), u_M = sum_j w_j u_j trilinear on the component's own grid.
!>   - coupling 'implicit' (image point 'mirror', d_M = d_G): the stencils hold other ghost nodes,
!>     so the ghost rows form a coupled system, solved by Jacobi sweeps over the ghost list to a
!>     tolerance. Jacobi (every new value from the previous sweep's values) rather than Gauss-Seidel
!>     so that the result does not depend on the ranks' ordering: 1 and 2 ranks agree to round-off.
!>     Stencil corners on another rank are read from copies of the neighbours' planes, exchanged
!>     whole before the first sweep; when any stencil reaches a ghost node of another rank, only the
!>     ghost values in those planes (the only values a sweep changes) travel after each sweep, in
!>     one gather with every rank's largest change (ghost_exchange_t: the same copies as a whole
!>     exchange and the same residual as a reduction, at one collective per sweep).
!>   - coupling 'explicit' (image point 'image', d_M = max(d_G, 1.5 h)): one evaluation of the row
!>     (G's own weight, where the stencil still holds G, on the diagonal as above).
!> - Loads by momentum balance (ibm-notes section 8.2): each imposition changes the momentum on the
!>   grid by rho dV sum (u_imposed - u_before) e_c over the ghost and interior nodes of the body
!>   (each component at its own nodes). Part of it goes to the fictitious fluid on the body's own
!>   nodes; the rest is what the body gives the real fluid. So the force on the body is
!>     F = -(1/dt) [sum over both impositions of rho dV sum (u_imposed - u_before) e_c]
!>         + (1/dt) rho dV sum_{nodes of the body at n+1} (u^{n+1} - u^n) e_c,
!>   the second term the discrete rate of change of the fictitious fluid's momentum, rho_f d/dt(V U)
!>   for a rigid body. Taken over the nodes the body holds at n+1, it also carries the momentum a
!>   node brings when it is covered or leaves when it is uncovered, so a change of status adds no
!>   spike u/dt to the force (docs/theory.md). The torque likewise with r x.
!> - Moving bodies (docs/theory.md, "Immersed boundary: moving bodies"): a node the body uncovers
!>   keeps its last ghost value (nothing here writes fluid nodes); the pressure of the sealed cells
!>   next to the fluid is extrapolated from the open cells after every step (ibm_extend_pressure),
!>   so that the incremental predictor's old gradient at an uncovered node is the fluid's; the
!>   nodes changing status and the load jumps they cause are counted (status_change_report_t).
module immersed_boundary
  use, intrinsic :: iso_fortran_env, only: int8, int64
  use mpi_f08, only: MPI_Sendrecv, MPI_Allreduce, MPI_Allgather, MPI_Allgatherv, MPI_IN_PLACE, MPI_SUM, MPI_MAX, &
                     MPI_INTEGER, MPI_STATUS_IGNORE
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use parallel_env, only: world, mpi_wp, global_max, n_ranks
  use periodic_box, only: minimum_image
  use fluid_grid, only: fluid_grid_t
  use halo_exchange, only: exchange_slab_halos
  use immersed_geometry, only: immersed_body_t, immersed_options_t, immersed_geometry_t, component_nodes_t, &
                               classify_nodes, node_position, node_ghost, node_fluid, fallback_count, saturated_count
  implicit none
  private
  public :: immersed_boundary_t, ibm_settings_t, imposition_report_t, status_change_report_t
  public :: ibm_set_bodies, ibm_impose, ibm_begin_step, ibm_step_loads, cell_divergence_max
  public :: ibm_extend_pressure, status_change_summary, ibm_fallback_rows

  !> The solid (ghost and interior) nodes of this rank's planes of one component as the previous
  !> classification listed them: its lists hold every solid node of the planes, so the status
  !> changes follow from these few thousand nodes, where a copy of the status fields and their
  !> comparison took three whole-field passes a step.
  type :: solid_nodes_t
    integer, allocatable :: node(:, :)   !< (3, n): i, j global, k local
  end type solid_nodes_t

  !> The ghost values one rank's sweeps send to one neighbour and receive from it (one direction of
  !> the plane exchange; plan_ghost_traffic): after the first whole exchange of the planes, a sweep
  !> changes only ghost values, so only those of the planes the neighbour copies need to travel.
  type :: ghost_traffic_t
    integer, allocatable :: outgoing(:, :)       !< (2, m): component, index in its ghost list
    integer, allocatable :: incoming(:, :)       !< (4, m): component, i, j, k in below | above
  end type ghost_traffic_t

  !> The traffic of the coupled (lockstep) sweeps, planned once per classification (the ghost lists
  !> change only then; both impositions of a step use it): after each sweep one gather carries every
  !> rank's block [largest change, values for the rank below, values for the rank above], so a sweep
  !> costs one collective where the two neighbour exchanges and the residual's reduction took three
  !> (each a wait for the slowest rank: the cost of a sweep on a shared machine is its waits).
  type :: ghost_exchange_t
    logical :: planned = .false.                 !< the plan belongs to the current classification
    type(ghost_traffic_t) :: downward, upward    !< to the rank below (its above planes), to the rank above
    integer, allocatable :: counts(:), displacements(:)   !< (n_ranks) blocks of the gather, 1 + down + up values
    integer, allocatable :: down_counts(:)       !< (n_ranks) values each rank sends down
    real(wp), allocatable :: send(:), receive(:) !< this rank's block, all blocks
  end type ghost_exchange_t

  !> The rigid velocity and the load bookkeeping of one node, for a solver that imposes the body rows itself
  public :: rigid_velocity, account
  !> The velocity a ghost row is built on (u_B, or the saturated Couette value), for the same solvers
  public :: ghost_surface_value

  !> Lever arms r (minimum image of the point - the body's centre, m) of one component's nodes,
  !> computed once per placement so that an imposition costs only U + Omega x r per node.
  type :: lever_arms_t
    real(wp), allocatable :: interior(:, :)   !< (3, n_interior), at the interior nodes
    real(wp), allocatable :: ghost(:, :)      !< (3, n_ghost), at the ghost nodes G
    real(wp), allocatable :: surface(:, :)    !< (3, n_ghost), at their surface points B
    !> (3, n_ghost), at the other body's surface point B' of a saturated row, from that body's centre (else 0)
    real(wp), allocatable :: opposite(:, :)
  end type lever_arms_t

  !> What the deck decides about the imposition.
  type :: ibm_settings_t
    character(len=16) :: coupling = 'implicit'   !< 'implicit' (pure mirror, sweeps) | 'explicit' (image point, one pass)
    real(wp) :: tolerance = 1.0e-12_wp           !< largest ghost change of the last sweep / velocity scale
    integer :: max_sweeps = 50                   !< sweeps before the run stops (implicit)
    real(wp) :: fluid_density = 1.0_wp           !< kg/m^3, rho_f of the loads
  end type ibm_settings_t

  !> What one imposition did (for the log).
  type :: imposition_report_t
    integer :: sweeps = 0               !< Jacobi sweeps (1 for the explicit coupling)
    integer :: exchanges = 0            !< plane exchanges and ghost-value gathers with the other ranks
    real(wp) :: residual = 0            !< largest ghost change in the last sweep / velocity scale
    real(wp) :: largest_change = 0      !< largest |u_imposed - u_before| over ghost and interior nodes / scale
    real(wp) :: velocity_scale = 0      !< m/s, the scale of residual and largest_change
  end type imposition_report_t

  !> Nodes that change status as the bodies move, and the load jumps they cause (docs/theory.md,
  !> "Immersed boundary: moving bodies"). The jump of a step is the change of the force beyond the
  !> trend of the previous step, |F^{n+1} - 2 F^n + F^{n-1}| (vector norm, the largest over the
  !> bodies; a smooth load gives O(dt^2), a spike s at one step gives 2 s), over the load scale, the
  !> root mean square of |F| over the steps so far. The first `settling_steps` steps (the start of
  !> the motion from rest) are left out of both. A jump at a step with status changes or right after
  !> one counts as a jump at a status change.
  type :: status_change_report_t
    integer :: uncovered = 0                  !< nodes (all components, all ranks) fluid at n+1, solid at n
    integer :: covered = 0                    !< nodes fluid at n, solid at n+1
    integer(int64) :: total_uncovered = 0, total_covered = 0   !< over the run
    integer :: steps_with_changes = 0         !< steps in which some node changed status
    integer :: steps = 0                      !< steps with loads
    integer :: settling_steps = 10            !< steps left out at the start
    real(wp) :: mean_square = 0               !< N^2, sum of |F|^2 (largest over the bodies) after the settling steps
    real(wp) :: last_jump = 0                 !< the last step's jump over the load scale
    real(wp) :: largest_jump_changes = 0      !< largest jump over the steps with status changes
    real(wp) :: largest_jump_steady = 0       !< largest jump over the other steps
    integer :: step_of_largest = 0            !< step (counted from the first with loads) of largest_jump_changes
    logical :: changed_before = .false.       !< nodes changed status in the previous step
  end type status_change_report_t

  type :: immersed_boundary_t
    type(ibm_settings_t) :: settings
    type(immersed_geometry_t) :: geometry
    type(immersed_body_t), allocatable :: bodies(:)
    real(wp), allocatable :: velocity(:, :)           !< (3, n) m/s, U of each body at the imposition's time
    real(wp), allocatable :: angular_velocity(:, :)   !< (3, n) rad/s, Omega
    real(wp), allocatable :: momentum_change(:, :)    !< (3, n) kg m/s added to the fluid this step
    real(wp), allocatable :: angular_change(:, :)     !< (3, n) kg m^2/s added to the fluid this step
    !> (6, n) momentum (1:3) and angular momentum (4:6) change of the fictitious fluid on each body's
    !> nodes over the step: this rank's part during the step, the global sum after ibm_step_loads
    real(wp), allocatable :: inertia_change(:, :)
    integer :: halo_planes = 0           !< planes beyond the slab that the stencils reach (every component)
    logical :: remote_ghosts = .false.   !< some stencil (on some rank) holds a ghost node of another rank
    logical :: stencils_leave_slab = .true.   !< some stencil (on some rank) reaches beyond its rank's slab
    type(ghost_exchange_t) :: exchange   !< the coupled sweeps' traffic (remote_ghosts), per classification
    real(wp), allocatable :: below(:, :, :, :), above(:, :, :, :)   !< copies of the neighbours' planes, per component
    real(wp), allocatable :: plane_buffer(:, :, :, :)   !< this rank's planes of the three components, as sent
    type(lever_arms_t) :: arms(3)        !< per component, for the current placement
    real(wp), allocatable :: arm_centres(:, :)   !< (3, n) the centres the lever arms were computed for
    type(status_change_report_t) :: changes      !< status changes and load jumps (moving bodies)
    real(wp), allocatable :: force_history(:, :, :)   !< (3, n, 2) N, the forces of the last two steps
    !> Work fields of ibm_extend_pressure (field layout, halos): 1 where the cell has a fluid face,
    !> and the values a cell offers to the cell below (above) it by linear extrapolation
    real(wp), allocatable :: cell_open(:, :, :), offer_down(:, :, :), offer_up(:, :, :)
  end type immersed_boundary_t

contains

  !> Place the bodies with their velocities (at the time level of the next imposition) and, when
  !> classify is true, classify the nodes again (collective). The first call always classifies.
  subroutine ibm_set_bodies(ibm, grid, bodies, velocity, angular_velocity, classify)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_body_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: velocity(:, :), angular_velocity(:, :)
    logical, intent(in) :: classify
    type(immersed_options_t) :: options
    integer :: n, c, g, planes, reach(2)
    logical :: remote
    character(len=200) :: text
    type(solid_nodes_t) :: previous(3)
    logical :: classified_before

    n = size(bodies)
    if (.not. allocated(ibm%bodies)) then
      allocate(ibm%velocity(3, n), ibm%angular_velocity(3, n), ibm%momentum_change(3, n), ibm%angular_change(3, n))
      allocate(ibm%inertia_change(6, n))
      ibm%momentum_change = 0; ibm%angular_change = 0; ibm%inertia_change = 0
    end if
    ibm%bodies = bodies
    ibm%velocity = velocity
    ibm%angular_velocity = angular_velocity
    if (.not. classify .and. allocated(ibm%arm_centres)) then
      ibm%changes%uncovered = 0
      ibm%changes%covered = 0
      ! Unchanged centres (a fixed or only spinning sphere): the lever arms stand.
      if (any(ibm%arm_centres(1, :) /= ibm%bodies(:)%centre(1)) .or. &
          any(ibm%arm_centres(2, :) /= ibm%bodies(:)%centre(2)) &
          .or. any(ibm%arm_centres(3, :) /= ibm%bodies(:)%centre(3))) call compute_lever_arms(ibm, grid)
      return
    end if

    select case (trim(ibm%settings%coupling))
    case ('implicit')
      options%image_point = 'mirror'
    case ('explicit')
      options%image_point = 'image'
    case default
      call fatal('immersed boundary: coupling = '''//trim(ibm%settings%coupling)//'''; allowed: implicit, explicit')
    end select
    classified_before = allocated(ibm%geometry%component(1)%status)
    if (classified_before) then
      do c = 1, 3
        associate (nodes => ibm%geometry%component(c))
          allocate(previous(c)%node(3, nodes%n_ghost + nodes%n_interior))
          do g = 1, nodes%n_ghost
            previous(c)%node(:, g) = nodes%ghost(g)%node
          end do
          previous(c)%node(:, nodes%n_ghost + 1:) = nodes%interior(:, 1:nodes%n_interior)
        end associate
      end do
    end if
    call classify_nodes(grid, bodies, options, ibm%geometry)
    ibm%exchange%planned = .false.
    call count_status_changes(ibm, previous, classified_before)
    ! One reduction for both: the planes the stencils reach (largest) and whether any stencil
    ! holds another rank's ghost node (as 0 / 1, the largest is the logical or).
    reach = 0
    do c = 1, 3
      reach(1) = max(reach(1), ibm%geometry%component(c)%halo_planes_needed)
      if (any_remote_ghost(ibm%geometry%component(c))) reach(2) = 1
    end do
    call MPI_Allreduce(MPI_IN_PLACE, reach, 2, MPI_INTEGER, MPI_MAX, world)
    planes = reach(1)
    remote = reach(2) > 0
    ibm%stencils_leave_slab = planes > 0
    planes = max(planes, 1)
    if (planes > grid%nz_local) then
      write(text, '(a,i0,a,i0,a)') 'immersed boundary: the ghost stencils reach ', planes, &
          ' planes beyond a rank''s slab of ', grid%nz_local, ' planes; use fewer ranks or more cells in z'
      call fatal(trim(text))
    end if
    ibm%remote_ghosts = remote
    if (planes /= ibm%halo_planes) then
      ibm%halo_planes = planes
      if (allocated(ibm%below)) deallocate(ibm%below, ibm%above)
      allocate(ibm%below(0:grid%nx + 1, 0:grid%ny + 1, 1 - planes:0, 3))
      allocate(ibm%above(0:grid%nx + 1, 0:grid%ny + 1, grid%nz_local + 1:grid%nz_local + planes, 3))
    end if
    call compute_lever_arms(ibm, grid)
  end subroutine ibm_set_bodies

  !> Nodes of this rank's planes whose fluid/solid status differs from the previous classification
  !> (its solid nodes in previous; none before the first one), summed over the ranks. Uncovered:
  !> the previous solid nodes that are fluid now; covered: the solid nodes now less those that were
  !> solid before, i.e. n_now - (n_before - uncovered).
  subroutine count_status_changes(ibm, previous, classified_before)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(solid_nodes_t), intent(in) :: previous(3)
    logical, intent(in) :: classified_before
    integer :: c, m, counts(2), uncovered
    counts = 0
    if (classified_before) then
      do c = 1, 3
        associate (now => ibm%geometry%component(c), before => previous(c)%node)
          uncovered = 0
          do m = 1, size(before, 2)
            if (now%status(before(1, m), before(2, m), before(3, m)) == node_fluid) uncovered = uncovered + 1
          end do
          counts(1) = counts(1) + uncovered
          counts(2) = counts(2) + now%n_ghost + now%n_interior - (size(before, 2) - uncovered)
        end associate
      end do
    end if
    call MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_INTEGER, MPI_SUM, world)
    ibm%changes%uncovered = counts(1)
    ibm%changes%covered = counts(2)
    ibm%changes%total_uncovered = ibm%changes%total_uncovered + counts(1)
    ibm%changes%total_covered = ibm%changes%total_covered + counts(2)
  end subroutine count_status_changes

  subroutine compute_lever_arms(ibm, grid)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    real(wp) :: box(3)
    integer :: c, m
    box = [grid%lx, grid%ly, grid%lz]
    if (allocated(ibm%arm_centres)) deallocate(ibm%arm_centres)
    allocate(ibm%arm_centres(3, size(ibm%bodies)))
    do m = 1, size(ibm%bodies)
      ibm%arm_centres(:, m) = ibm%bodies(m)%centre
    end do
    do c = 1, 3
      associate (nodes => ibm%geometry%component(c), arms => ibm%arms(c))
        if (allocated(arms%interior)) deallocate(arms%interior, arms%ghost, arms%surface, arms%opposite)
        allocate(arms%interior(3, nodes%n_interior), arms%ghost(3, nodes%n_ghost), arms%surface(3, nodes%n_ghost), &
                 arms%opposite(3, nodes%n_ghost))
        do m = 1, nodes%n_interior
          arms%interior(:, m) = minimum_image(node_position(grid, c, nodes%interior(1, m), nodes%interior(2, m), &
                                                            nodes%interior(3, m)) - ibm%bodies(nodes%interior_body(m))%centre, box)
        end do
        do m = 1, nodes%n_ghost
          arms%ghost(:, m) = minimum_image(nodes%ghost(m)%position - ibm%bodies(nodes%ghost(m)%body)%centre, box)
          arms%surface(:, m) = minimum_image(nodes%ghost(m)%surface_point - ibm%bodies(nodes%ghost(m)%body)%centre, box)
          arms%opposite(:, m) = 0.0_wp
          if (nodes%ghost(m)%saturated) arms%opposite(:, m) = &
            minimum_image(nodes%ghost(m)%opposite_point - ibm%bodies(nodes%ghost(m)%opposite_body)%centre, box)
        end do
      end associate
    end do
  end subroutine compute_lever_arms

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

  !> The load jump of the step (status_change_report_t), counted apart for the steps in which
  !> nodes changed status; the force history moves on.
  subroutine record_load_jump(changes, history, force)
    type(status_change_report_t), intent(inout) :: changes
    real(wp), allocatable, intent(inout) :: history(:, :, :)   !< (3, n, 2): F^n, F^{n-1}
    real(wp), intent(in) :: force(:, :)
    integer :: n
    real(wp) :: jump, largest, scale
    changes%steps = changes%steps + 1
    if (changes%uncovered + changes%covered > 0) changes%steps_with_changes = changes%steps_with_changes + 1
    if (.not. allocated(history)) then
      allocate(history(3, size(force, 2), 2))
      history = 0
    end if
    changes%last_jump = 0
    if (changes%steps > changes%settling_steps) then
      largest = 0
      jump = 0
      do n = 1, size(force, 2)
        largest = max(largest, norm2(force(:, n)))
        jump = max(jump, norm2(force(:, n) - 2.0_wp * history(:, n, 1) + history(:, n, 2)))
      end do
      changes%mean_square = changes%mean_square + largest**2
      scale = sqrt(changes%mean_square / (changes%steps - changes%settling_steps))
      if (changes%steps > changes%settling_steps + 2 .and. scale > 0.0_wp) then
        changes%last_jump = jump / scale
        ! A spike at step n shows in the jumps of steps n and n + 1.
        if (changes%uncovered + changes%covered > 0 .or. changes%changed_before) then
          if (changes%last_jump > changes%largest_jump_changes) changes%step_of_largest = changes%steps
          changes%largest_jump_changes = max(changes%largest_jump_changes, changes%last_jump)
        else
          changes%largest_jump_steady = max(changes%largest_jump_steady, changes%last_jump)
        end if
      end if
    end if
    history(:, :, 2) = history(:, :, 1)
    history(:, :, 1) = force
    changes%changed_before = changes%uncovered + changes%covered > 0
  end subroutine record_load_jump

  !> One log line on the status changes of a run and the load jumps (status_change_report_t).
  function status_change_summary(changes) result(line)
    type(status_change_report_t), intent(in) :: changes
    character(len=:), allocatable :: line
    character(len=320) :: text
    write(text, '(a,i0,a,i0,a,i0,a,i0,a,es9.2,a,i0,a,es9.2,a)') 'immersed boundary: status changes: ', &
        changes%total_uncovered, ' nodes uncovered and ', changes%total_covered, ' covered in ', &
        changes%steps_with_changes, ' of ', changes%steps, ' steps; largest load jump |F(n+1) - 2 F(n) + F(n-1)| ', &
        changes%largest_jump_changes, ' of the rms load at a status change (step ', changes%step_of_largest, &
        '), ', changes%largest_jump_steady, ' at other steps'
    line = trim(text)
  end function status_change_summary

  !> The pressure of the sealed cells next to the fluid (collective; call after the projection,
  !> with the classification of the velocity just projected and every pressure halo current).
  !> A sealed cell has no fluid face: its pressure enters no fluid node's gradient, and the
  !> projection, which sees the cut cells' divergence every step, lets it grow without bound (the
  !> increments phi are harmonic inside the body). When the body moves, a sealed cell next to the
  !> fluid can open in the next step, and its pressure then enters the incremental predictor's
  !> -(dt/rho) G p^{n-1/2} at the uncovered face. So every sealed cell with an open neighbour
  !> takes the mean over its open neighbours N1 = C + e (the six directions e) of the linear
  !> extrapolation 2 p(N1) - p(N1 + e) when N1 + e is open too, else p(N1): the gradient at a
  !> face that opens is then the gradient one cell further out (docs/theory.md, moving bodies).
  !> Open cells are never changed, so fixed bodies give the same velocity to the bit.
  subroutine ibm_extend_pressure(ibm, grid, pressure)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(inout) :: grid
    real(wp), intent(inout) :: pressure(0:, 0:, 0:)
    integer :: i, j, k, nx, ny, nzl, d, count
    real(wp) :: total
    integer, parameter :: step_x(4) = [1, -1, 0, 0], step_y(4) = [0, 0, 1, -1]
    logical, allocatable :: near_i(:), near_j(:), near_k(:)
    nx = grid%nx; ny = grid%ny; nzl = grid%nz_local
    if (.not. allocated(ibm%cell_open)) then
      allocate(ibm%cell_open, ibm%offer_down, ibm%offer_up, mold=pressure)
      ibm%cell_open = 1; ibm%offer_down = 0; ibm%offer_up = 0
    end if
    ! Only cells within 3 of a solid node are visited (a tensor product of index ranges, like the
    ! classification's); cell_open stays 1 elsewhere: a body moves less than a cell per step, so
    ! the cells it sealed before lie in the new range.
    call near_ranges(ibm, grid, 3, near_i, near_j, near_k)
    associate (su => ibm%geometry%component(1)%status, sv => ibm%geometry%component(2)%status, &
               sw => ibm%geometry%component(3)%status, open => ibm%cell_open)
      ! A cell is open when one of its six faces (u(i-1), u(i), v(j-1), v(j), w(k-1), w(k)) is a fluid node.
      do k = 1, nzl
        if (.not. near_k(k)) cycle
        do j = 1, ny
          if (.not. near_j(j)) cycle
          do i = 1, nx
            if (.not. near_i(i)) cycle
            open(i, j, k) = merge(1.0_wp, 0.0_wp, su(i - 1, j, k) == node_fluid .or. su(i, j, k) == node_fluid .or. &
                                  sv(i, j - 1, k) == node_fluid .or. sv(i, j, k) == node_fluid .or. &
                                  sw(i, j, k - 1) == node_fluid .or. sw(i, j, k) == node_fluid)
          end do
        end do
      end do
      call exchange_slab_halos(grid%slab, open)
      ! What each open cell offers its z neighbours (these may be on the next rank).
      do k = 1, nzl
        if (.not. near_k(k)) cycle
        do j = 1, ny
          if (.not. near_j(j)) cycle
          do i = 1, nx
            if (.not. near_i(i)) cycle
            if (open(i, j, k) > 0.5_wp) then
              ibm%offer_down(i, j, k) = extrapolated(pressure(i, j, k), pressure(i, j, k + 1), open(i, j, k + 1))
              ibm%offer_up(i, j, k) = extrapolated(pressure(i, j, k), pressure(i, j, k - 1), open(i, j, k - 1))
            end if
          end do
        end do
      end do
      call exchange_slab_halos(grid%slab, ibm%offer_down, ibm%offer_up)
      do k = 1, nzl
        if (.not. near_k(k)) cycle
        do j = 1, ny
          if (.not. near_j(j)) cycle
          do i = 1, nx
            if (.not. near_i(i)) cycle
            if (open(i, j, k) > 0.5_wp) cycle
            total = 0
            count = 0
            do d = 1, 4
              associate (i1 => wrap(i + step_x(d), nx), j1 => wrap(j + step_y(d), ny), &
                         i2 => wrap(i + 2 * step_x(d), nx), j2 => wrap(j + 2 * step_y(d), ny))
                if (open(i1, j1, k) > 0.5_wp) then
                  total = total + extrapolated(pressure(i1, j1, k), pressure(i2, j2, k), open(i2, j2, k))
                  count = count + 1
                end if
              end associate
            end do
            if (open(i, j, k + 1) > 0.5_wp) then
              total = total + ibm%offer_down(i, j, k + 1)
              count = count + 1
            end if
            if (open(i, j, k - 1) > 0.5_wp) then
              total = total + ibm%offer_up(i, j, k - 1)
              count = count + 1
            end if
            if (count > 0) pressure(i, j, k) = total / count
          end do
        end do
      end do
    end associate
    call exchange_slab_halos(grid%slab, pressure)
  contains
    !> 2 p1 - p2 when the cell beyond (p2) is open, else p1.
    pure real(wp) function extrapolated(p1, p2, open2) result(value)
      real(wp), intent(in) :: p1, p2, open2
      if (open2 > 0.5_wp) then
        value = 2.0_wp * p1 - p2
      else
        value = p1
      end if
    end function extrapolated
    pure integer function wrap(i, n)
      integer, intent(in) :: i, n
      wrap = modulo(i - 1, n) + 1
    end function wrap
  end subroutine ibm_extend_pressure

  !> The i, j (global) and k (local, 1..nz_local) indices within `margin` of a ghost or interior
  !> node of any component on this rank (periodic in i and j).
  subroutine near_ranges(ibm, grid, margin, near_i, near_j, near_k)
    type(immersed_boundary_t), intent(in) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: margin
    logical, allocatable, intent(out) :: near_i(:), near_j(:), near_k(:)
    logical, allocatable :: solid_i(:), solid_j(:), solid_k(:)
    integer :: c, m, s
    allocate(solid_i(grid%nx), solid_j(grid%ny), solid_k(grid%nz_local))
    solid_i = .false.; solid_j = .false.; solid_k = .false.
    do c = 1, 3
      associate (nodes => ibm%geometry%component(c))
        do m = 1, nodes%n_ghost
          call mark(nodes%ghost(m)%node)
        end do
        do m = 1, nodes%n_interior
          call mark(nodes%interior(:, m))
        end do
        ! Solid nodes of the neighbouring ranks' edge planes: this rank's edge cells feed their
        ! sealed cells (cell_open, offers through the halo exchange).
        call mark_plane(nodes%status(1:grid%nx, 1:grid%ny, 0), 1)
        call mark_plane(nodes%status(1:grid%nx, 1:grid%ny, grid%nz_local + 1), grid%nz_local)
      end associate
    end do
    allocate(near_i(grid%nx), near_j(grid%ny), near_k(grid%nz_local))
    near_i = solid_i; near_j = solid_j; near_k = solid_k
    do s = 1, margin
      near_i = near_i .or. cshift(solid_i, s) .or. cshift(solid_i, -s)
      near_j = near_j .or. cshift(solid_j, s) .or. cshift(solid_j, -s)
      near_k(1 + s:) = near_k(1 + s:) .or. solid_k(:grid%nz_local - s)
      near_k(:grid%nz_local - s) = near_k(:grid%nz_local - s) .or. solid_k(1 + s:)
    end do
  contains
    subroutine mark(node)
      integer, intent(in) :: node(3)
      solid_i(node(1)) = .true.
      solid_j(node(2)) = .true.
      solid_k(node(3)) = .true.
    end subroutine mark
    subroutine mark_plane(status, k)
      integer(int8), intent(in) :: status(:, :)
      integer, intent(in) :: k
      if (all(status == node_fluid)) return
      solid_i = solid_i .or. any(status /= node_fluid, dim=2)
      solid_j = solid_j .or. any(status /= node_fluid, dim=1)
      solid_k(k) = .true.
    end subroutine mark_plane
  end subroutine near_ranges

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
      real(wp) :: added(3), factor
      integer :: m, n
      factor = sign * ibm%settings%fluid_density * grid%cell_volume
      associate (nodes => ibm%geometry%component(c), arms => ibm%arms(c))
        do m = 1, nodes%n_interior
          n = nodes%interior_body(m)
          added = 0
          added(c) = factor * field(nodes%interior(1, m), nodes%interior(2, m), nodes%interior(3, m))
          ibm%inertia_change(1:3, n) = ibm%inertia_change(1:3, n) + added
          ibm%inertia_change(4:6, n) = ibm%inertia_change(4:6, n) + cross(arms%interior(:, m), added)
        end do
        do m = 1, nodes%n_ghost
          n = nodes%ghost(m)%body
          added = 0
          added(c) = factor * field(nodes%ghost(m)%node(1), nodes%ghost(m)%node(2), nodes%ghost(m)%node(3))
          ibm%inertia_change(1:3, n) = ibm%inertia_change(1:3, n) + added
          ibm%inertia_change(4:6, n) = ibm%inertia_change(4:6, n) + cross(arms%ghost(:, m), added)
        end do
      end associate
    end subroutine add_component
  end subroutine add_body_momentum

  !> Impose the interior and ghost values on u, v, w (collective) and refresh their halos; the
  !> momentum the imposition adds goes into the step's load bookkeeping. Stops the run when the
  !> implicit ghost rows do not converge in max_sweeps sweeps.
  subroutine ibm_impose(ibm, grid, u, v, w, report)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(inout) :: grid
    real(wp), intent(inout) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    type(imposition_report_t), intent(out) :: report
    real(wp) :: change(3), scale(3), limit
    real(wp), allocatable :: before(:, :)   ! (max ghosts, 3) ghost values before the imposition
    real(wp), allocatable :: surface(:, :)  ! u_B of each ghost
    integer :: c, sweep, max_sweeps, n_max
    character(len=240) :: text

    n_max = max(1, maxval([(ibm%geometry%component(c)%n_ghost, c = 1, 3)]))
    allocate(before(n_max, 3), surface(n_max, 3))
    change = 0
    scale = 0
    call impose_interior(ibm, grid, 1, u, change(1), scale(1))
    call impose_interior(ibm, grid, 2, v, change(2), scale(2))
    call impose_interior(ibm, grid, 3, w, change(3), scale(3))
    call surface_velocities(ibm, grid, 1, u, surface(:, 1), before(:, 1), scale(1))
    call surface_velocities(ibm, grid, 2, v, surface(:, 2), before(:, 2), scale(2))
    call surface_velocities(ibm, grid, 3, w, surface(:, 3), before(:, 3), scale(3))
    report%velocity_scale = max(global_max(maxval(scale)), tiny(1.0_wp))

    max_sweeps = 1
    if (ibm%settings%coupling == 'implicit') max_sweeps = ibm%settings%max_sweeps
    report%residual = huge(1.0_wp)
    ! The neighbours' planes are read only by stencils that leave the slab (none: nothing to copy).
    if (ibm%stencils_leave_slab .or. ibm%remote_ghosts) then
      call exchange_planes(ibm, grid, u, v, w)
      report%exchanges = report%exchanges + 1
    end if
    sweep = 0
    if (ibm%remote_ghosts .or. max_sweeps == 1) then
      ! Coupled across ranks: every sweep waits for the neighbours' ghost values and the global residual.
      if (ibm%remote_ghosts .and. max_sweeps > 1 .and. .not. ibm%exchange%planned) call plan_ghost_traffic(ibm, grid)
      call lockstep_sweeps()
    else
      ! No stencil reads another rank's ghost nodes, so each rank's ghost rows are a system of their
      ! own: a rank sweeps until its own residual meets the tolerance, the ranks then agree on the
      ! largest count, those that stopped earlier catch up, and the global residual is checked once.
      ! The result is that of lockstep sweeps with a global residual every sweep (the same sweep
      ! count and values), with one reduction where lockstep takes one per sweep.
      do while (sweep < max_sweeps)
        call sweep_once()
        if (limit / report%velocity_scale <= ibm%settings%tolerance) exit
      end do
      report%sweeps = global_max_integer(sweep)
      do while (sweep < report%sweeps)
        call sweep_once()
      end do
      report%residual = global_max(limit) / report%velocity_scale
      if (.not. (report%residual <= ibm%settings%tolerance)) call lockstep_sweeps()
    end if
    if (ibm%settings%coupling == 'implicit' .and. .not. (report%residual <= ibm%settings%tolerance)) then
      write(text, '(a,i0,a,es10.3,a,es10.3,a)') 'immersed boundary: the ghost rows did not converge in ', &
          max_sweeps, ' sweeps (residual ', report%residual, ' > tolerance ', ibm%settings%tolerance, &
          '); raise &bodies max_sweeps, loosen ghost_tolerance, or check that no body is thinner than 4 cells'
      call fatal(trim(text))
    end if

    call account_ghosts(ibm, grid, 1, u, before(:, 1), change(1))
    call account_ghosts(ibm, grid, 2, v, before(:, 2), change(2))
    call account_ghosts(ibm, grid, 3, w, before(:, 3), change(3))
    report%largest_change = global_max(maxval(change)) / report%velocity_scale
    call exchange_slab_halos(grid%slab, u, v, w)
  contains

    !> One Jacobi sweep of the three components' ghost rows on this rank (limit: the largest change).
    subroutine sweep_once()
      limit = 0
      call jacobi_sweep(ibm, 1, u, surface(:, 1), limit)
      call jacobi_sweep(ibm, 2, v, surface(:, 2), limit)
      call jacobi_sweep(ibm, 3, w, surface(:, 3), limit)
      sweep = sweep + 1
    end subroutine sweep_once

    !> Sweeps on every rank together until the global residual meets the tolerance or max_sweeps.
    !> With ghost nodes coupled across ranks, one gather after each sweep brings the neighbours'
    !> new ghost values (for the next sweep's stencils) and the largest change over all ranks: the
    !> values and the residual of a neighbour exchange before the sweep plus a reduction after it,
    !> so the sweeps, their count and every value are the same.
    subroutine lockstep_sweeps()
      real(wp) :: largest
      do while (sweep < max_sweeps)
        call sweep_once()
        report%sweeps = sweep
        if (ibm%remote_ghosts .and. max_sweeps > 1) then
          call gather_sweep_result(ibm, grid, u, v, w, limit, largest)
          report%exchanges = report%exchanges + 1
        else
          largest = global_max(limit)
        end if
        report%residual = largest / report%velocity_scale
        if (report%residual <= ibm%settings%tolerance) exit
      end do
    end subroutine lockstep_sweeps
  end subroutine ibm_impose

  !> Ghost rows over all ranks whose image point was moved back because another body is near
  !> (fallback rows) and, among them, the saturated Couette rows (immersed_geometry), in one
  !> reduction (collective).
  subroutine ibm_fallback_rows(ibm, fallbacks, saturated)
    type(immersed_boundary_t), intent(in) :: ibm
    integer, intent(out) :: fallbacks, saturated
    integer :: counts(2)
    counts = [fallback_count(ibm%geometry), saturated_count(ibm%geometry)]
    call MPI_Allreduce(MPI_IN_PLACE, counts, 2, MPI_INTEGER, MPI_SUM, world)
    fallbacks = counts(1)
    saturated = counts(2)
  end subroutine ibm_fallback_rows

  !> The largest of an integer over the ranks (collective).
  integer function global_max_integer(local) result(largest)
    integer, intent(in) :: local
    largest = local
    call MPI_Allreduce(MPI_IN_PLACE, largest, 1, MPI_INTEGER, MPI_MAX, world)
  end function global_max_integer

  !> The velocity a ghost row of component `component` is built on (m/s): u_B, the body's rigid
  !> velocity at B, whose row reads u_G = (1 + kappa) u_B - kappa u_M; for a saturated row (kappa = 0)
  !> the Couette value across the sub-cell gap, u_B - c (u_B' - u_B), with u_B' the other body's rigid
  !> velocity at B' (immersed_geometry, c = couette_gain).
  pure real(wp) function ghost_surface_value(ibm, component, g) result(value)
    type(immersed_boundary_t), intent(in) :: ibm
    integer, intent(in) :: component, g
    real(wp) :: opposite
    associate (ghost => ibm%geometry%component(component)%ghost(g), arms => ibm%arms(component))
      value = rigid_velocity(ibm, ghost%body, component, arms%surface(:, g))
      if (ghost%saturated) then
        opposite = rigid_velocity(ibm, ghost%opposite_body, component, arms%opposite(:, g))
        value = value - ghost%couette_gain * (opposite - value)
      end if
    end associate
  end function ghost_surface_value

  !> Rigid-body velocity component `component` of body n at lever arm r: (U + Omega x r)_c (m/s).
  pure real(wp) function rigid_velocity(ibm, n, component, r) result(value)
    type(immersed_boundary_t), intent(in) :: ibm
    integer, intent(in) :: n, component
    real(wp), intent(in) :: r(3)
    associate (omega => ibm%angular_velocity(:, n))
      select case (component)
      case (1)
        value = ibm%velocity(1, n) + omega(2) * r(3) - omega(3) * r(2)
      case (2)
        value = ibm%velocity(2, n) + omega(3) * r(1) - omega(1) * r(3)
      case default
        value = ibm%velocity(3, n) + omega(1) * r(2) - omega(2) * r(1)
      end select
    end associate
  end function rigid_velocity

  !> Largest |div u| (1/s) over this rank's cells and over all ranks (collective): after the
  !> re-imposition it is non-zero only in the cut cells, whose faces carry fictitious ghost values.
  function cell_divergence_max(grid, u, v, w) result(largest)
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp) :: largest
    integer :: i, j, k
    largest = 0
    do k = 1, grid%nz_local
      do j = 1, grid%ny
        do i = 1, grid%nx
          largest = max(largest, abs((u(i, j, k) - u(i - 1, j, k)) / grid%dx + (v(i, j, k) - v(i, j - 1, k)) / grid%dy &
                                     + (w(i, j, k) - w(i, j, k - 1)) / grid%dz))
        end do
      end do
    end do
    largest = global_max(largest)
  end function cell_divergence_max

  ! ---------------------------------------------------------------------------------------------

  subroutine impose_interior(ibm, grid, component, field, change, scale)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: component
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    real(wp), intent(inout) :: change, scale
    integer :: m, n, node(3)
    real(wp) :: value, delta
    associate (nodes => ibm%geometry%component(component))
      do m = 1, nodes%n_interior
        node = nodes%interior(:, m)
        n = nodes%interior_body(m)
        value = rigid_velocity(ibm, n, component, ibm%arms(component)%interior(:, m))
        delta = value - field(node(1), node(2), node(3))
        field(node(1), node(2), node(3)) = value
        call account(ibm, grid, n, component, ibm%arms(component)%interior(:, m), delta)
        change = max(change, abs(delta))
        scale = max(scale, abs(value))
      end do
    end associate
  end subroutine impose_interior

  !> u_B of every ghost of one component, the ghost values before the imposition, and the scale.
  subroutine surface_velocities(ibm, grid, component, field, surface, before, scale)
    type(immersed_boundary_t), intent(in) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: component
    real(wp), intent(in) :: field(0:, 0:, 0:)
    real(wp), intent(out) :: surface(:), before(:)
    real(wp), intent(inout) :: scale
    integer :: g
    associate (nodes => ibm%geometry%component(component))
      do g = 1, nodes%n_ghost
        associate (ghost => nodes%ghost(g))
          surface(g) = ghost_surface_value(ibm, component, g)
          before(g) = field(ghost%node(1), ghost%node(2), ghost%node(3))
          scale = max(scale, abs(surface(g)), abs(before(g)))
        end associate
      end do
    end associate
  end subroutine surface_velocities

  !> One Jacobi sweep of the ghost rows of one component: every new value from the values before
  !> the sweep; `limit` takes the largest change.
  subroutine jacobi_sweep(ibm, component, field, surface, limit)
    type(immersed_boundary_t), intent(in) :: ibm
    integer, intent(in) :: component
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    real(wp), intent(in) :: surface(:)
    real(wp), intent(inout) :: limit
    real(wp), allocatable :: updated(:)
    real(wp) :: kappa, self_weight, neighbours
    integer :: g, corner, k
    associate (nodes => ibm%geometry%component(component))
      allocate(updated(nodes%n_ghost))
      do g = 1, nodes%n_ghost
        associate (ghost => nodes%ghost(g))
          kappa = ghost%extrapolation
          neighbours = 0
          self_weight = 0
          do corner = 1, 8
            if (corner == ghost%self_corner) then
              self_weight = ghost%weight(corner)
              cycle
            end if
            ! The corner's local plane, continued beyond the slab (lower corner + bit).
            k = ghost%node(3) + ghost%lower_offset(3) + (corner - 1) / 4
            neighbours = neighbours + ghost%weight(corner) * &
                         plane_value(ibm, component, field, ghost%stencil(1, corner), ghost%stencil(2, corner), k)
          end do
          updated(g) = ((1.0_wp + kappa) * surface(g) - kappa * neighbours) / (1.0_wp + kappa * self_weight)
        end associate
      end do
      do g = 1, nodes%n_ghost
        associate (node => nodes%ghost(g)%node)
          limit = max(limit, abs(updated(g) - field(node(1), node(2), node(3))))
          field(node(1), node(2), node(3)) = updated(g)
        end associate
      end do
    end associate
  end subroutine jacobi_sweep

  !> Value at i, j (global) and local plane k, which may lie beyond the slab (copied planes).
  pure real(wp) function plane_value(ibm, component, field, i, j, k) result(value)
    type(immersed_boundary_t), intent(in) :: ibm
    integer, intent(in) :: component
    real(wp), intent(in) :: field(0:, 0:, 0:)
    integer, intent(in) :: i, j, k
    if (k < 1) then
      value = ibm%below(i, j, k, component)
    else if (k > ubound(field, 3) - 1) then
      value = ibm%above(i, j, k, component)
    else
      value = field(i, j, k)
    end if
  end function plane_value

  !> Add the final ghost changes of one component to the load bookkeeping.
  subroutine account_ghosts(ibm, grid, component, field, before, change)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: component
    real(wp), intent(in) :: field(0:, 0:, 0:)
    real(wp), intent(in) :: before(:)
    real(wp), intent(inout) :: change
    integer :: g
    real(wp) :: delta
    do g = 1, ibm%geometry%component(component)%n_ghost
      associate (ghost => ibm%geometry%component(component)%ghost(g))
        delta = field(ghost%node(1), ghost%node(2), ghost%node(3)) - before(g)
        call account(ibm, grid, ghost%body, component, ibm%arms(component)%ghost(:, g), delta)
        change = max(change, abs(delta))
      end associate
    end do
  end subroutine account_ghosts

  !> Momentum rho dV delta e_c and angular momentum rho dV r x (delta e_c) added at the node of
  !> lever arm r.
  subroutine account(ibm, grid, n, component, r, delta)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: n, component
    real(wp), intent(in) :: r(3), delta
    real(wp) :: added(3)
    added = 0
    added(component) = ibm%settings%fluid_density * grid%cell_volume * delta
    ibm%momentum_change(:, n) = ibm%momentum_change(:, n) + added
    ibm%angular_change(:, n) = ibm%angular_change(:, n) + cross(r, added)
  end subroutine account

  !> Copy the planes the stencils reach beyond the slab from the neighbouring ranks (periodic;
  !> with one rank the slab's own planes), for all three components: one message per direction
  !> with the three components (plane_buffer), one wait instead of three.
  subroutine exchange_planes(ibm, grid, u, v, w)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    integer :: h, nzl
    h = ibm%halo_planes
    nzl = grid%nz_local
    ! Shaped like the copies it fills on the other side (kept between calls: no allocation per step).
    if (allocated(ibm%plane_buffer)) then
      if (any(shape(ibm%plane_buffer) /= shape(ibm%above))) deallocate(ibm%plane_buffer)
    end if
    if (.not. allocated(ibm%plane_buffer)) allocate(ibm%plane_buffer(0:grid%nx + 1, 0:grid%ny + 1, h, 3))
    associate (buffer => ibm%plane_buffer)
      buffer(:, :, :, 1) = u(:, :, 1:h)
      buffer(:, :, :, 2) = v(:, :, 1:h)
      buffer(:, :, :, 3) = w(:, :, 1:h)
      call MPI_Sendrecv(buffer, size(buffer), mpi_wp, grid%slab%rank_below, 410, ibm%above, size(ibm%above), mpi_wp, &
                        grid%slab%rank_above, 410, world, MPI_STATUS_IGNORE)
      buffer(:, :, :, 1) = u(:, :, nzl - h + 1:nzl)
      buffer(:, :, :, 2) = v(:, :, nzl - h + 1:nzl)
      buffer(:, :, :, 3) = w(:, :, nzl - h + 1:nzl)
      call MPI_Sendrecv(buffer, size(buffer), mpi_wp, grid%slab%rank_above, 420, ibm%below, size(ibm%below), mpi_wp, &
                        grid%slab%rank_below, 420, world, MPI_STATUS_IGNORE)
    end associate
  end subroutine exchange_planes

  !> Which ghost values travel in each direction between sweeps (collective; once per
  !> classification, ibm%exchange): this rank's ghosts in its lowest halo_planes planes go to the
  !> rank below (its `above` copies), those in its highest planes to the rank above (its `below`
  !> copies); each rank sends the other where the values go (k as the receiver's plane index: the
  !> receiver's nz_local added for `above`), and every rank learns the layout of the sweeps' gather.
  subroutine plan_ghost_traffic(ibm, grid)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer :: c, g, k, h, nzl, n_down, n_up, counts(2), r
    integer, allocatable :: where_down(:, :), where_up(:, :), sizes(:, :)
    associate (downward => ibm%exchange%downward, upward => ibm%exchange%upward)
      h = ibm%halo_planes
      nzl = grid%nz_local
      n_down = 0
      n_up = 0
      do c = 1, 3
        associate (nodes => ibm%geometry%component(c))
          n_down = n_down + count([(nodes%ghost(g)%node(3) <= h, g = 1, nodes%n_ghost)])
          n_up = n_up + count([(nodes%ghost(g)%node(3) > nzl - h, g = 1, nodes%n_ghost)])
        end associate
      end do
      if (allocated(downward%outgoing)) deallocate(downward%outgoing, upward%outgoing, downward%incoming, upward%incoming)
      allocate(downward%outgoing(2, n_down), upward%outgoing(2, n_up), where_down(4, n_down), where_up(4, n_up))
      n_down = 0
      n_up = 0
      do c = 1, 3
        associate (nodes => ibm%geometry%component(c))
          do g = 1, nodes%n_ghost
            k = nodes%ghost(g)%node(3)
            if (k <= h) then
              n_down = n_down + 1
              downward%outgoing(:, n_down) = [c, g]
              where_down(:, n_down) = [c, nodes%ghost(g)%node(1:2), k]          ! + the receiver's nz_local
            end if
            if (k > nzl - h) then
              n_up = n_up + 1
              upward%outgoing(:, n_up) = [c, g]
              where_up(:, n_up) = [c, nodes%ghost(g)%node(1:2), k - nzl]       ! in 1 - h .. 0
            end if
          end do
        end associate
      end do
      ! Downward values arrive from the rank above and upward ones from the rank below.
      call MPI_Sendrecv([n_down], 1, MPI_INTEGER, grid%slab%rank_below, 430, counts(1), 1, MPI_INTEGER, &
                        grid%slab%rank_above, 430, world, MPI_STATUS_IGNORE)
      call MPI_Sendrecv([n_up], 1, MPI_INTEGER, grid%slab%rank_above, 431, counts(2), 1, MPI_INTEGER, &
                        grid%slab%rank_below, 431, world, MPI_STATUS_IGNORE)
      allocate(downward%incoming(4, counts(1)), upward%incoming(4, counts(2)))
      call MPI_Sendrecv(where_down, 4 * n_down, MPI_INTEGER, grid%slab%rank_below, 432, downward%incoming, &
                        4 * counts(1), MPI_INTEGER, grid%slab%rank_above, 432, world, MPI_STATUS_IGNORE)
      call MPI_Sendrecv(where_up, 4 * n_up, MPI_INTEGER, grid%slab%rank_above, 433, upward%incoming, &
                        4 * counts(2), MPI_INTEGER, grid%slab%rank_below, 433, world, MPI_STATUS_IGNORE)
      downward%incoming(4, :) = downward%incoming(4, :) + nzl
    end associate
    ! The gather's blocks: [largest change, n_down values, n_up values] of every rank.
    allocate(sizes(2, 0:n_ranks - 1))
    call MPI_Allgather([n_down, n_up], 2, MPI_INTEGER, sizes, 2, MPI_INTEGER, world)
    associate (exchange => ibm%exchange)
      exchange%counts = [(1 + sizes(1, r) + sizes(2, r), r = 0, n_ranks - 1)]
      exchange%down_counts = sizes(1, :)
      exchange%displacements = [(sum(exchange%counts(1:r)), r = 0, n_ranks - 1)]
      if (allocated(exchange%send)) deallocate(exchange%send, exchange%receive)
      allocate(exchange%send(1 + n_down + n_up), exchange%receive(sum(exchange%counts)))
      exchange%planned = .true.
    end associate
  end subroutine plan_ghost_traffic

  !> After a coupled sweep (collective): one gather of every rank's block (ghost_exchange_t) puts
  !> the ghost values the neighbours sent into this rank's plane copies (what exchange_planes would
  !> bring now: a sweep changes only ghost values) and returns the largest change over the ranks.
  subroutine gather_sweep_result(ibm, grid, u, v, w, limit, largest)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: limit
    real(wp), intent(out) :: largest
    integer :: m, n_down, from_above, from_below
    associate (exchange => ibm%exchange)
      n_down = size(exchange%downward%outgoing, 2)
      exchange%send(1) = limit
      call pack_values(exchange%downward, exchange%send(2:1 + n_down))
      call pack_values(exchange%upward, exchange%send(2 + n_down:))
      call MPI_Allgatherv(exchange%send, size(exchange%send), mpi_wp, exchange%receive, exchange%counts, &
                          exchange%displacements, mpi_wp, world)
      ! The largest of the blocks' first entries: the value a MAX reduction gives (max is exact).
      largest = maxval(exchange%receive(exchange%displacements + 1))
      ! The rank above's values for the rank below it, then the rank below's for the rank above it.
      from_above = exchange%displacements(grid%slab%rank_above + 1) + 1
      do m = 1, size(exchange%downward%incoming, 2)
        associate (at => exchange%downward%incoming(:, m))
          ibm%above(at(2), at(3), at(4), at(1)) = exchange%receive(from_above + m)
        end associate
      end do
      from_below = exchange%displacements(grid%slab%rank_below + 1) + 1 + exchange%down_counts(grid%slab%rank_below + 1)
      do m = 1, size(exchange%upward%incoming, 2)
        associate (at => exchange%upward%incoming(:, m))
          ibm%below(at(2), at(3), at(4), at(1)) = exchange%receive(from_below + m)
        end associate
      end do
    end associate
  contains
    subroutine pack_values(traffic, values)
      type(ghost_traffic_t), intent(in) :: traffic
      real(wp), intent(out) :: values(:)
      integer :: n
      do n = 1, size(values)
        associate (c => traffic%outgoing(1, n), g => traffic%outgoing(2, n))
          associate (node => ibm%geometry%component(c)%ghost(g)%node)
            select case (c)
            case (1)
              values(n) = u(node(1), node(2), node(3))
            case (2)
              values(n) = v(node(1), node(2), node(3))
            case default
              values(n) = w(node(1), node(2), node(3))
            end select
          end associate
        end associate
      end do
    end subroutine pack_values
  end subroutine gather_sweep_result

  pure logical function any_remote_ghost(nodes)
    type(component_nodes_t), intent(in) :: nodes
    integer :: g
    any_remote_ghost = .false.
    do g = 1, nodes%n_ghost
      if (any(.not. nodes%ghost(g)%stencil_local .and. nodes%ghost(g)%stencil_status == node_ghost)) then
        any_remote_ghost = .true.
        return
      end if
    end do
  end function any_remote_ghost

  pure function cross(a, b) result(c)
    real(wp), intent(in) :: a(3), b(3)
    real(wp) :: c(3)
    c = [a(2) * b(3) - a(3) * b(2), a(3) * b(1) - a(1) * b(3), a(1) * b(2) - a(2) * b(1)]
  end function cross
end module immersed_boundary
