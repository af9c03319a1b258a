!> The immersed-boundary imposition on the staggered velocity components (Mark & van Wachem 2008;
!> docs/theory.md, "Immersed boundary: imposition and loads"): interior nodes take the rigid
!> velocity u_rigid = U + Omega x r, ghost nodes G their row
!>   (1 + kappa w_G) u_G = (1 + kappa) u_B - kappa sum_{j /= G} w_j u_j        (immersed_boundary)
!> with the stencil, weights and kappa = d_G/d_M of immersed_geometry.
!> - coupling 'implicit' (image point 'mirror', d_M = d_G): the stencils hold other ghost nodes,
!>   so the ghost rows form a coupled system, solved by Jacobi sweeps over the ghost list to a
!>   tolerance. Jacobi (every new value from the previous sweep's values) rather than Gauss-Seidel
!>   so that the result does not depend on the ranks' ordering: 1 and 2 ranks agree to round-off.
!>   Stencil corners on another rank are read from copies of the neighbours' planes
!>   (immersed_ghost_exchange).
!> - coupling 'explicit' (image point 'image', d_M = max(d_G, 1.5 h)): one evaluation of the row
!>   (G's own weight, where the stencil still holds G, on the diagonal as above).
!> The momentum each imposition adds to the grid goes into the load bookkeeping (immersed_loads).
module immersed_imposition
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_MAX, MPI_INTEGER
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use parallel_env, only: world, global_max
  use fluid_grid, only: fluid_grid_t
  use halo_exchange, only: exchange_slab_halos
  use immersed_ghost_exchange, only: exchange_planes, plan_ghost_traffic, gather_sweep_result
  use immersed_boundary, only: immersed_boundary_t, imposition_report_t, ghost_rows_t, rigid_velocity, ghost_surface_value
  use immersed_loads, only: account
  use immersed_geometry, only: node_ghost
  implicit none
  private
  public :: ibm_impose

contains

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

    do c = 1, 3
      if (ibm%rows(c)%packed_from /= ibm%geometry%classifications) call pack_rows(ibm, grid, c)
    end do
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
    if (ibm%planes%stencils_leave_slab .or. ibm%planes%remote_ghosts) then
      call exchange_planes(ibm%planes, grid, u, v, w)
      report%exchanges = report%exchanges + 1
    end if
    sweep = 0
    if (ibm%planes%remote_ghosts .or. max_sweeps == 1) then
      ! Coupled across ranks: every sweep waits for the neighbours' ghost values and the global residual.
      if (ibm%planes%remote_ghosts .and. max_sweeps > 1 .and. .not. ibm%planes%exchange%planned) &
        call plan_ghost_traffic(ibm%planes, grid, ibm%geometry)
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
      call jacobi_sweep(ibm, 1, u, surface(:, 1), sweep == 0, limit)
      call jacobi_sweep(ibm, 2, v, surface(:, 2), sweep == 0, limit)
      call jacobi_sweep(ibm, 3, w, surface(:, 3), sweep == 0, limit)
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
        if (ibm%planes%remote_ghosts .and. max_sweeps > 1) then
          call gather_sweep_result(ibm%planes, grid, ibm%geometry, u, v, w, limit, largest)
          report%exchanges = report%exchanges + 1
        else
          largest = global_max(limit)
        end if
        report%residual = largest / report%velocity_scale
        if (report%residual <= ibm%settings%tolerance) exit
      end do
    end subroutine lockstep_sweeps
  end subroutine ibm_impose

  !> The largest of an integer over the ranks (collective).
  integer function global_max_integer(local) result(largest)
    integer, intent(in) :: local
    largest = local
    call MPI_Allreduce(MPI_IN_PLACE, largest, 1, MPI_INTEGER, MPI_MAX, world)
  end function global_max_integer

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

  !> Pack the ghost rows of one component for the sweeps (ghost_rows_t, immersed_boundary) from
  !> the records of the current classification.
  subroutine pack_rows(ibm, grid, component)
    type(immersed_boundary_t), intent(inout) :: ibm
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: component
    integer :: g, corner, k, n_ghost, stride_j, stride_k, plane_size, k_low
    integer, allocatable :: next(:)   ! (0:n_ghost) the next place of a moving corner that reads row r (0: the others)
    associate (nodes => ibm%geometry%component(component), rows => ibm%rows(component))
      n_ghost = nodes%n_ghost
      if (allocated(rows%node)) then
        if (size(rows%node) < n_ghost) deallocate(rows%node, rows%source, rows%weight, rows%values, rows%kappa, &
                                                  rows%self_weight, rows%moving, rows%reader_start, rows%changed, &
                                                  rows%active, rows%is_active)
      end if
      if (.not. allocated(rows%node)) then
        allocate(rows%node(size(nodes%ghost)), rows%source(8, size(nodes%ghost)), &
          rows%weight(8, size(nodes%ghost)), rows%values(8, size(nodes%ghost)), rows%kappa(size(nodes%ghost)), &
          rows%self_weight(size(nodes%ghost)), rows%moving(2, 8 * size(nodes%ghost)), &
          rows%reader_start(size(nodes%ghost) + 1), rows%changed(size(nodes%ghost)), &
          rows%active(size(nodes%ghost)), rows%is_active(size(nodes%ghost)))
        rows%is_active = .false.
      end if
      rows%n_changed = 0
      ! The moving corners grouped by the row they read: counted (next(r), r = 0 for the others),
      ! then placed in the second loop below.
      allocate(next(0:n_ghost))
      next = 0
      do g = 1, n_ghost
        associate (ghost => nodes%ghost(g))
          do corner = 1, 8
            if (corner == ghost%self_corner .or. ghost%stencil_status(corner) /= node_ghost) cycle
            next(ghost%stencil_ghost(corner)) = next(ghost%stencil_ghost(corner)) + 1
          end do
        end associate
      end do
      rows%reader_start(1) = 1
      do k = 1, n_ghost
        rows%reader_start(k + 1) = rows%reader_start(k) + next(k)
      end do
      rows%n_moving = rows%reader_start(n_ghost + 1) - 1 + next(0)
      next(1:n_ghost) = rows%reader_start(1:n_ghost)
      next(0) = rows%reader_start(n_ghost + 1)
      ! The field's layout (0:nx+1, 0:ny+1, 0:nz_local+1) and the planes' (0:nx+1, 0:ny+1, halo planes).
      stride_j = grid%nx + 2
      stride_k = stride_j * (grid%ny + 2)
      plane_size = 0
      k_low = 0
      if (allocated(ibm%planes%below)) then
        plane_size = size(ibm%planes%below(:, :, :, component))
        k_low = lbound(ibm%planes%below, 3)
      end if
      do g = 1, n_ghost
        associate (ghost => nodes%ghost(g))
          rows%node(g) = flat(ghost%node(1), ghost%node(2), ghost%node(3))
          rows%kappa(g) = ghost%extrapolation
          rows%self_weight(g) = 0
          do corner = 1, 8
            rows%weight(corner, g) = ghost%weight(corner)
            if (corner == ghost%self_corner) then
              rows%self_weight(g) = ghost%weight(corner)
              rows%source(corner, g) = 0
              cycle
            end if
            ! A ghost node (of this rank or, in the copied planes, of a neighbour) changes in the sweeps.
            if (ghost%stencil_status(corner) == node_ghost) then
              rows%moving(:, next(ghost%stencil_ghost(corner))) = [corner, g]
              next(ghost%stencil_ghost(corner)) = next(ghost%stencil_ghost(corner)) + 1
            end if
            ! The corner's local plane, continued beyond the slab (lower corner + bit).
            k = ghost%node(3) + ghost%lower_offset(3) + (corner - 1) / 4
            if (k < 1) then
              rows%source(corner, g) = -(flat(ghost%stencil(1, corner), ghost%stencil(2, corner), k - k_low))
            else if (k > grid%nz_local) then
              rows%source(corner, g) = -(plane_size + flat(ghost%stencil(1, corner), ghost%stencil(2, corner), &
                                                           k - grid%nz_local - 1))
            else
              rows%source(corner, g) = flat(ghost%stencil(1, corner), ghost%stencil(2, corner), k)
            end if
          end do
        end associate
      end do
      rows%packed_from = ibm%geometry%classifications
    end associate
  contains
    !> Position of (i, j, k) in an array of layout (0:nx+1, 0:ny+1, 0:) flattened.
    pure integer function flat(i, j, k)
      integer, intent(in) :: i, j, k
      flat = 1 + i + stride_j * j + stride_k * k
    end function flat
  end subroutine pack_rows

  !> One Jacobi sweep of the ghost rows of one component: every new value from the values before
  !> the sweep; `limit` takes the largest change. The first sweep of an imposition reads every
  !> stencil value and evaluates every row; a later one re-reads only the ghost corners whose value
  !> changed in the sweep before and evaluates only the rows that read them: a row whose inputs did
  !> not change would give its value again to the bit, so the sweeps, their count and every value
  !> are those of evaluating every row every sweep.
  subroutine jacobi_sweep(ibm, component, field, surface, first, limit)
    type(immersed_boundary_t), intent(inout) :: ibm
    integer, intent(in) :: component
    real(wp), intent(inout) :: field(0:, 0:, 0:)
    real(wp), intent(in) :: surface(:)
    logical, intent(in) :: first
    real(wp), intent(inout) :: limit
    real(wp) :: no_planes(0)
    if (ibm%geometry%component(component)%n_ghost == 0) return
    if (allocated(ibm%planes%below)) then
      call sweep_rows(ibm%rows(component), ibm%geometry%component(component)%n_ghost, field, &
                      ibm%planes%below(:, :, :, component), ibm%planes%above(:, :, :, component), &
                      size(ibm%planes%below(:, :, :, component)), surface, first, limit)
    else   ! no copied planes (then no stencil leaves the slab)
      call sweep_rows(ibm%rows(component), ibm%geometry%component(component)%n_ghost, field, no_planes, no_planes, &
                      0, surface, first, limit)
    end if
  end subroutine jacobi_sweep

  !> The sweep of jacobi_sweep on the packed rows, with the field and the component's copied planes
  !> seen flattened (the layouts of pack_rows): the stencil values are gathered into rows%values
  !> (all of them when `first`, else the ghost corners whose value changed), then each row to
  !> evaluate is evaluated from them in the order of its corners, as from the field.
  subroutine sweep_rows(rows, n_ghost, field, below, above, plane_size, surface, first, limit)
    type(ghost_rows_t), intent(inout) :: rows
    integer, intent(in) :: n_ghost, plane_size   !< plane_size: the values in below (and in above)
    real(wp), intent(inout) :: field(*)
    real(wp), intent(in) :: below(*), above(*)
    real(wp), intent(in) :: surface(:)
    logical, intent(in) :: first
    real(wp), intent(inout) :: limit
    real(wp), allocatable :: updated(:)
    real(wp) :: neighbours, value
    integer :: g, corner, m, i, r, n_active
    if (first) then
      do g = 1, n_ghost
        do corner = 1, 8
          if (rows%source(corner, g) /= 0) rows%values(corner, g) = source_value(rows%source(corner, g))
        end do
        rows%active(g) = g
      end do
      n_active = n_ghost
    else
      n_active = 0
      do i = 1, rows%n_changed
        r = rows%changed(i)
        do m = rows%reader_start(r), rows%reader_start(r + 1) - 1
          associate (corner => rows%moving(1, m), g => rows%moving(2, m))
            rows%values(corner, g) = field(rows%node(r))
            call activate(g)
          end associate
        end do
      end do
      ! The copied planes (and ghost nodes without a row here) change outside this rank's sweep:
      ! compared as stored, bit for bit.
      do m = rows%reader_start(n_ghost + 1), rows%n_moving
        associate (corner => rows%moving(1, m), g => rows%moving(2, m))
          value = source_value(rows%source(corner, g))
          if (value /= rows%values(corner, g)) then   ! (a NaN compares unequal: re-evaluated)
            rows%values(corner, g) = value
            call activate(g)
          end if
        end associate
      end do
      ! Many rows: evaluated in storage order (the rows' arrays streamed, not gathered).
      if (8 * n_active > n_ghost) then
        n_active = 0
        do g = 1, n_ghost
          if (.not. rows%is_active(g)) cycle
          n_active = n_active + 1
          rows%active(n_active) = g
        end do
      end if
      rows%is_active(rows%active(1:n_active)) = .false.
    end if
    allocate(updated(n_active))
    do i = 1, n_active
      g = rows%active(i)
      neighbours = 0
      do corner = 1, 8
        if (rows%source(corner, g) == 0) cycle
        neighbours = neighbours + rows%weight(corner, g) * rows%values(corner, g)
      end do
      updated(i) = ((1.0_wp + rows%kappa(g)) * surface(g) - rows%kappa(g) * neighbours) / &
                   (1.0_wp + rows%kappa(g) * rows%self_weight(g))
    end do
    rows%n_changed = 0
    do i = 1, n_active
      g = rows%active(i)
      limit = max(limit, abs(updated(i) - field(rows%node(g))))
      if (updated(i) /= field(rows%node(g))) then
        rows%n_changed = rows%n_changed + 1
        rows%changed(rows%n_changed) = g
      end if
      field(rows%node(g)) = updated(i)
    end do
  contains
    !> Mark row g for evaluation in this sweep.
    subroutine activate(g)
      integer, intent(in) :: g
      if (rows%is_active(g)) return
      rows%is_active(g) = .true.
      n_active = n_active + 1
      rows%active(n_active) = g
    end subroutine activate

    !> The value at a packed source position (> 0 field, < 0 planes: below, then above).
    real(wp) function source_value(source) result(value)
      integer, intent(in) :: source
      if (source > 0) then
        value = field(source)
      else if (-source <= plane_size) then
        value = below(-source)
      else
        value = above(-source - plane_size)
      end if
    end function source_value
  end subroutine sweep_rows

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
end module immersed_imposition
