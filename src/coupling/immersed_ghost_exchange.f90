!> The immersed boundary's traffic between ranks: the copies of the neighbouring ranks' planes
!> that the ghost stencils reach beyond a rank's slab, and the ghost values the coupled Jacobi
!> sweeps exchange (docs/theory.md, "Immersed boundary: imposition and loads").
!>
!> The ghost row of a node G reads the trilinear stencil of its image point (Mark & van Wachem
!> 2008), whose corners may lie on the planes of the rank below or above. Those planes are copied
!> whole before the first sweep (exchange_planes). When a stencil also holds a ghost node of another
!> rank, the ghost rows of the ranks form one coupled system: a sweep then changes only ghost values,
!> so after each sweep only the ghost values in the copied planes travel, in one gather that also
!> carries every rank's largest change (ghost_exchange_t): the same copies as a whole exchange and
!> the same residual as a reduction, at one collective per sweep.
module immersed_ghost_exchange
  use mpi_f08, only: MPI_Sendrecv, MPI_Allreduce, MPI_Allgather, MPI_Allgatherv, MPI_IN_PLACE, MPI_MAX, &
                     MPI_INTEGER, MPI_STATUS_IGNORE
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use parallel_env, only: world, mpi_wp, n_ranks
  use fluid_grid, only: fluid_grid_t
  use immersed_geometry, only: immersed_geometry_t, component_nodes_t, node_ghost
  implicit none
  private
  public :: ghost_planes_t, ghost_planes_classified, exchange_planes, plan_ghost_traffic, gather_sweep_result

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

  !> The planes beyond this rank's slab that the ghost stencils read, and how they are kept current.
  type :: ghost_planes_t
    integer :: halo_planes = 0           !< planes beyond the slab that the stencils reach (every component)
    logical :: remote_ghosts = .false.   !< some stencil (on some rank) holds a ghost node of another rank
    logical :: stencils_leave_slab = .true.   !< some stencil (on some rank) reaches beyond its rank's slab
    type(ghost_exchange_t) :: exchange   !< the coupled sweeps' traffic (remote_ghosts), per classification
    real(wp), allocatable :: below(:, :, :, :), above(:, :, :, :)   !< copies of the neighbours' planes, per component
    real(wp), allocatable :: plane_buffer(:, :, :, :)   !< this rank's planes of the three components, as sent
  end type ghost_planes_t

contains

  !> After a classification of the nodes (collective): the planes the stencils reach beyond the
  !> slabs and whether any stencil holds another rank's ghost node, over all ranks; the plane
  !> copies are sized for them and the sweeps' traffic is to be planned again. Stops the run when
  !> the stencils reach beyond the neighbouring rank's slab.
  subroutine ghost_planes_classified(planes, grid, geometry)
    type(ghost_planes_t), intent(inout) :: planes
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_geometry_t), intent(in) :: geometry
    integer :: c, halo, reach(2)
    logical :: remote
    character(len=200) :: text
    planes%exchange%planned = .false.
    ! One reduction for both: the planes the stencils reach (largest) and whether any stencil
    ! holds another rank's ghost node (as 0 / 1, the largest is the logical or).
    reach = 0
    do c = 1, 3
      reach(1) = max(reach(1), geometry%component(c)%halo_planes_needed)
      if (any_remote_ghost(geometry%component(c))) reach(2) = 1
    end do
    call MPI_Allreduce(MPI_IN_PLACE, reach, 2, MPI_INTEGER, MPI_MAX, world)
    halo = reach(1)
    remote = reach(2) > 0
    planes%stencils_leave_slab = halo > 0
    halo = max(halo, 1)
    if (halo > grid%nz_local) then
      write(text, '(a,i0,a,i0,a)') 'immersed boundary: the ghost stencils reach ', halo, &
          ' planes beyond a rank''s slab of ', grid%nz_local, ' planes; use fewer ranks or more cells in z'
      call fatal(trim(text))
    end if
    planes%remote_ghosts = remote
    if (halo /= planes%halo_planes) then
      planes%halo_planes = halo
      if (allocated(planes%below)) deallocate(planes%below, planes%above)
      allocate(planes%below(0:grid%nx + 1, 0:grid%ny + 1, 1 - halo:0, 3))
      allocate(planes%above(0:grid%nx + 1, 0:grid%ny + 1, grid%nz_local + 1:grid%nz_local + halo, 3))
    end if
  end subroutine ghost_planes_classified

  !> Copy the planes the stencils reach beyond the slab from the neighbouring ranks (periodic;
  !> with one rank the slab's own planes), for all three components: one message per direction
  !> with the three components (plane_buffer), one wait instead of three.
  subroutine exchange_planes(planes, grid, u, v, w)
    type(ghost_planes_t), intent(inout) :: planes
    type(fluid_grid_t), intent(in) :: grid
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    integer :: h, nzl
    h = planes%halo_planes
    nzl = grid%nz_local
    ! Shaped like the copies it fills on the other side (kept between calls: no allocation per step).
    if (allocated(planes%plane_buffer)) then
      if (any(shape(planes%plane_buffer) /= shape(planes%above))) deallocate(planes%plane_buffer)
    end if
    if (.not. allocated(planes%plane_buffer)) allocate(planes%plane_buffer(0:grid%nx + 1, 0:grid%ny + 1, h, 3))
    associate (buffer => planes%plane_buffer)
      buffer(:, :, :, 1) = u(:, :, 1:h)
      buffer(:, :, :, 2) = v(:, :, 1:h)
      buffer(:, :, :, 3) = w(:, :, 1:h)
      call MPI_Sendrecv(buffer, size(buffer), mpi_wp, grid%slab%rank_below, 410, planes%above, size(planes%above), mpi_wp, &
                        grid%slab%rank_above, 410, world, MPI_STATUS_IGNORE)
      buffer(:, :, :, 1) = u(:, :, nzl - h + 1:nzl)
      buffer(:, :, :, 2) = v(:, :, nzl - h + 1:nzl)
      buffer(:, :, :, 3) = w(:, :, nzl - h + 1:nzl)
      call MPI_Sendrecv(buffer, size(buffer), mpi_wp, grid%slab%rank_above, 420, planes%below, size(planes%below), mpi_wp, &
                        grid%slab%rank_below, 420, world, MPI_STATUS_IGNORE)
    end associate
  end subroutine exchange_planes

  !> Which ghost values travel in each direction between sweeps (collective; once per
  !> classification, planes%exchange): this rank's ghosts in its lowest halo_planes planes go to the
  !> rank below (its `above` copies), those in its highest planes to the rank above (its `below`
  !> copies); each rank sends the other where the values go (k as the receiver's plane index: the
  !> receiver's nz_local added for `above`), and every rank learns the layout of the sweeps' gather.
  subroutine plan_ghost_traffic(planes, grid, geometry)
    type(ghost_planes_t), intent(inout) :: planes
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_geometry_t), intent(in) :: geometry
    integer :: c, g, k, h, nzl, n_down, n_up, counts(2), r
    integer, allocatable :: where_down(:, :), where_up(:, :), sizes(:, :)
    associate (downward => planes%exchange%downward, upward => planes%exchange%upward)
      h = planes%halo_planes
      nzl = grid%nz_local
      n_down = 0
      n_up = 0
      do c = 1, 3
        associate (nodes => geometry%component(c))
          n_down = n_down + count([(nodes%ghost(g)%node(3) <= h, g = 1, nodes%n_ghost)])
          n_up = n_up + count([(nodes%ghost(g)%node(3) > nzl - h, g = 1, nodes%n_ghost)])
        end associate
      end do
      if (allocated(downward%outgoing)) deallocate(downward%outgoing, upward%outgoing, downward%incoming, upward%incoming)
      allocate(downward%outgoing(2, n_down), upward%outgoing(2, n_up), where_down(4, n_down), where_up(4, n_up))
      n_down = 0
      n_up = 0
      do c = 1, 3
        associate (nodes => geometry%component(c))
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
    associate (exchange => planes%exchange)
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
  subroutine gather_sweep_result(planes, grid, geometry, u, v, w, limit, largest)
    type(ghost_planes_t), intent(inout) :: planes
    type(fluid_grid_t), intent(in) :: grid
    type(immersed_geometry_t), intent(in) :: geometry
    real(wp), intent(in) :: u(0:, 0:, 0:), v(0:, 0:, 0:), w(0:, 0:, 0:)
    real(wp), intent(in) :: limit
    real(wp), intent(out) :: largest
    integer :: m, n_down, from_above, from_below
    associate (exchange => planes%exchange)
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
          planes%above(at(2), at(3), at(4), at(1)) = exchange%receive(from_above + m)
        end associate
      end do
      from_below = exchange%displacements(grid%slab%rank_below + 1) + 1 + exchange%down_counts(grid%slab%rank_below + 1)
      do m = 1, size(exchange%upward%incoming, 2)
        associate (at => exchange%upward%incoming(:, m))
          planes%below(at(2), at(3), at(4), at(1)) = exchange%receive(from_below + m)
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
          associate (node => geometry%component(c)%ghost(g)%node)
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
end module immersed_ghost_exchange
