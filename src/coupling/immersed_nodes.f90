!> The immersed boundary's node records, shared by the classification (immersed_geometry) and the
!> ghost records (ghost_records): the status of a velocity node (fluid, ghost, interior), the bodies
!> and options as the geometry sees them, a ghost node's record with everything its ghost row needs,
!> one velocity component's classification on this rank, and the positions of the staggered (MAC)
!> velocity nodes (docs/theory.md, "Immersed boundary geometry").
module immersed_nodes
  use, intrinsic :: iso_fortran_env, only: int8
  use agglo_kinds, only: wp
  use fluid_grid, only: fluid_grid_t, x_centre, y_centre, z_centre, x_face, y_face, z_face
  use spheroid, only: spheroid_t
  use icosphere_mesh, only: icosphere_mesh_t
  implicit none
  private
  public :: immersed_body_t, immersed_options_t, ghost_node_t, component_nodes_t
  public :: node_position, thin_dimension_cells, wrap, ghost_row_diagonal
  public :: node_fluid, node_ghost, node_interior

  integer(int8), parameter :: node_fluid = 0_int8, node_ghost = 1_int8, node_interior = 2_int8

  !> One rigid body as the geometry sees it.
  type :: immersed_body_t
    type(spheroid_t) :: shape                  !< semi-axes (spheroid.f90)
    real(wp) :: centre(3) = 0.0_wp             !< m, lab frame (any periodic image)
    real(wp) :: orientation(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]   !< unit quaternion, body -> lab
    !> &bodies geometry = 'mesh': solid test, B and n from this triangulation (mesh_distance); level -1: analytic
    type(icosphere_mesh_t) :: mesh
  end type immersed_body_t

  !> How the image point is placed.
  type :: immersed_options_t
    character(len=16) :: image_point = 'mirror'  !< 'mirror': d_M = d_G; 'image': d_M = max(d_G, image_distance_cells h_max)
    real(wp) :: image_distance_cells = 1.5_wp    !< cells (of the largest spacing), for 'image'
    !> cells (of the largest spacing): a fallback row whose gap s is below this takes the saturated Couette value
    real(wp) :: saturation_gap_cells = 0.5_wp
    !> .true.: the exact tests only where they can decide (see "Work per body" above); .false.: every
    !> node of each body's bounding box and every other body (the reference: the same nodes and records)
    logical :: band = .true.
  end type immersed_options_t

  !> A ghost node of one velocity component, with everything its ghost row needs.
  type :: ghost_node_t
    integer :: node(3) = 0                 !< i, j global; k local to this rank's slab (1..nz_local)
    integer :: body = 0                    !< index of the body it belongs to
    real(wp) :: position(3) = 0.0_wp       !< m, G
    real(wp) :: surface_point(3) = 0.0_wp  !< m, B, in the periodic image frame of G
    real(wp) :: normal(3) = 0.0_wp         !< outward unit normal at B
    real(wp) :: distance = 0.0_wp          !< m, d_G = |G - B|
    real(wp) :: image_point(3) = 0.0_wp    !< m, M = B + d_M n, in the periodic image frame of G
    real(wp) :: image_distance = 0.0_wp    !< m, d_M = |M - B|
    real(wp) :: extrapolation = 0.0_wp     !< kappa = d_G/d_M (1 for the pure mirror; 0 when M = B)
    logical :: fallback = .false.          !< M moved back because the image segment entered another body
    !> fallback row with 0 < s < s_min: u_G = u_B - couette_gain (u_B' - u_B), no fluid node (kappa = 0)
    logical :: saturated = .false.
    integer :: opposite_body = 0           !< the other body of a saturated row (its B'), else 0
    real(wp) :: opposite_point(3) = 0.0_wp !< m, B' = B + s n, in the periodic image frame of G (saturated rows)
    real(wp) :: couette_gain = 0.0_wp      !< c = d_G/max(s, s_min) (saturated rows), else 0
    integer :: lower_offset(3) = 0         !< index of the stencil's lower corner minus the index of G
    integer :: stencil(3, 8) = 0           !< global i, j, k of the 8 nodes, wrapped into 1..n
    real(wp) :: weight(8) = 0.0_wp         !< trilinear weights (sum 1)
    integer(int8) :: stencil_status(8) = node_fluid   !< node_fluid, node_ghost or node_interior
    logical :: stencil_local(8) = .false.  !< the node is in this rank's planes
    integer :: stencil_ghost(8) = 0        !< its index in this component's ghost list (local ghosts), else 0
    integer :: self_corner = 0             !< the corner that is G itself (its weight w_G), 0 if none
  end type ghost_node_t

  !> Classification of one velocity component's nodes on this rank.
  type :: component_nodes_t
    integer :: component = 0                       !< 1 = u (x faces), 2 = v (y faces), 3 = w (z faces)
    !> node_fluid/ghost/interior over the field layout (0:nx+1, 0:ny+1, 0:nz_local+1), halos included
    integer(int8), allocatable :: status(:, :, :)
    integer :: n_ghost = 0, n_interior = 0
    type(ghost_node_t), allocatable :: ghost(:)     !< (1:n_ghost in use; the storage may be longer)
    integer, allocatable :: interior(:, :)          !< (3, 1:n_interior in use): i, j global, k local
    integer, allocatable :: interior_body(:)        !< (1:n_interior in use)
    integer :: n_fallback = 0                      !< ghosts whose image point was moved back (another body)
    integer :: n_overlap = 0                       !< ghosts whose surface point lies inside another body
    integer :: n_saturated = 0                     !< fallback ghosts below the saturation gap (Couette rows)
    integer :: halo_planes_needed = 0              !< planes beyond this rank's slab that the stencils reach
  end type component_nodes_t

contains

  !> The diagonal entry of a ghost row (Mark & van Wachem 2008, Eq. 7): 1 + kappa w_G, w_G the
  !> weight of G in its own stencil.
  pure real(wp) function ghost_row_diagonal(ghost)
    type(ghost_node_t), intent(in) :: ghost
    ghost_row_diagonal = 1.0_wp
    if (ghost%self_corner > 0) ghost_row_diagonal = 1.0_wp + ghost%extrapolation * ghost%weight(ghost%self_corner)
  end function ghost_row_diagonal

  !> Position (m) of node (i, j, k) of velocity component `component` (1 u, 2 v, 3 w), i and j
  !> global, k local to this rank (any integers: the positions continue beyond the box).
  pure function node_position(grid, component, i, j, k) result(x)
    type(fluid_grid_t), intent(in) :: grid
    integer, intent(in) :: component, i, j, k
    real(wp) :: x(3)
    x = [x_centre(grid, i), y_centre(grid, j), z_centre(grid, k)]
    select case (component)
    case (1)
      x(1) = x_face(grid, i)
    case (2)
      x(2) = y_face(grid, j)
    case (3)
      x(3) = z_face(grid, k)
    end select
  end function node_position

  !> Thinnest dimension of a body (2 min(a, b)) in cells of the largest grid spacing: the ghost
  !> layers of two opposite faces overlap when it is small (the disk of r = 50 um, aspect 5, is 2.2
  !> cells thick at 64^3 in a 1 mm box).
  pure function thin_dimension_cells(shape, grid) result(cells)
    type(spheroid_t), intent(in) :: shape
    type(fluid_grid_t), intent(in) :: grid
    real(wp) :: cells
    cells = 2.0_wp * min(shape%a, shape%b) / max(grid%dx, grid%dy, grid%dz)
  end function thin_dimension_cells

  !> Periodic index in 1..n.
  elemental integer function wrap(i, n)
    integer, intent(in) :: i, n
    if (i >= 1 .and. i <= n) then   ! most indices: no integer division
      wrap = i
    else
      wrap = modulo(i - 1, n) + 1
    end if
  end function wrap

end module immersed_nodes
