!> Placement of the bodies on the staggered grid: their position and rigid velocity at the time of
!> the next imposition, the classification of every velocity node as fluid, ghost or interior
!> (immersed_geometry: surface point, image point and trilinear stencil of each ghost node, after
!> Mark & van Wachem 2008), the lever arms r of the rigid velocity U + Omega x r at the nodes, and
!> the count of the nodes that change status as the bodies move (docs/theory.md, "Immersed
!> boundary: geometry" and "Immersed boundary: moving bodies").
module immersed_placement
  use mpi_f08, only: MPI_Allreduce, MPI_IN_PLACE, MPI_SUM, MPI_INTEGER
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use parallel_env, only: world
  use periodic_box, only: minimum_image
  use fluid_grid, only: fluid_grid_t
  use immersed_geometry, only: immersed_body_t, immersed_options_t, classify_nodes, node_position, node_fluid
  use immersed_ghost_exchange, only: ghost_planes_classified
  use immersed_boundary, only: immersed_boundary_t
  implicit none
  private
  public :: ibm_set_bodies

  !> The solid (ghost and interior) nodes of this rank's planes of one component as the previous
  !> classification listed them: its lists hold every solid node of the planes, so the status
  !> changes follow from these few thousand nodes, where a copy of the status fields and their
  !> comparison took three whole-field passes a step.
  type :: solid_nodes_t
    integer, allocatable :: node(:, :)   !< (3, n): i, j global, k local
  end type solid_nodes_t

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
    integer :: n, c, g
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
    call count_status_changes(ibm, previous, classified_before)
    call ghost_planes_classified(ibm%planes, grid, ibm%geometry)
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
    real(wp) :: box(3), x(3), axis_x(grid%nx), axis_y(grid%ny), axis_z(grid%nz_local)
    integer :: c, m, i
    box = [grid%lx, grid%ly, grid%lz]
    if (allocated(ibm%arm_centres)) deallocate(ibm%arm_centres)
    allocate(ibm%arm_centres(3, size(ibm%bodies)))
    do m = 1, size(ibm%bodies)
      ibm%arm_centres(:, m) = ibm%bodies(m)%centre
    end do
    do c = 1, 3
      associate (nodes => ibm%geometry%component(c), arms => ibm%arms(c))
        ! Kept while long enough, as the node lists are (immersed_geometry).
        if (allocated(arms%interior)) then
          if (size(arms%interior, 2) < nodes%n_interior .or. size(arms%ghost, 2) < nodes%n_ghost) &
            deallocate(arms%interior, arms%ghost, arms%surface, arms%opposite)
        end if
        if (.not. allocated(arms%interior)) &
          allocate(arms%interior(3, size(nodes%interior, 2)), arms%ghost(3, size(nodes%ghost)), &
                   arms%surface(3, size(nodes%ghost)), arms%opposite(3, size(nodes%ghost)))
        ! The nodes' coordinates along each axis (a node's position is the three of its indices).
        do i = 1, grid%nx
          x = node_position(grid, c, i, 1, 1)
          axis_x(i) = x(1)
        end do
        do i = 1, grid%ny
          x = node_position(grid, c, 1, i, 1)
          axis_y(i) = x(2)
        end do
        do i = 1, grid%nz_local
          x = node_position(grid, c, 1, 1, i)
          axis_z(i) = x(3)
        end do
        do m = 1, nodes%n_interior
          associate (centre => ibm%bodies(nodes%interior_body(m))%centre)
            arms%interior(1, m) = minimum_image(axis_x(nodes%interior(1, m)) - centre(1), box(1))
            arms%interior(2, m) = minimum_image(axis_y(nodes%interior(2, m)) - centre(2), box(2))
            arms%interior(3, m) = minimum_image(axis_z(nodes%interior(3, m)) - centre(3), box(3))
          end associate
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
end module immersed_placement
