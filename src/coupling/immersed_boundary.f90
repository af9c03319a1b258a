!> The immersed boundary's state: the bodies, their rigid motion, the settings and reports of the
!> imposition, and the rigid velocity the ghost and interior rows are built on (docs/theory.md,
!> "Immersed boundary: imposition and loads"). The modules that act on it:
!> - immersed_placement: place the bodies, classify the nodes (immersed_geometry), lever arms;
!> - immersed_imposition: the ghost and interior rows, by Jacobi sweeps or one explicit pass;
!> - immersed_loads: force and torque on the bodies by momentum balance;
!> - immersed_ghost_exchange: the neighbouring ranks' planes and ghost values the stencils read;
!> - immersed_pressure_extension: the pressure of sealed cells next to the fluid (moving bodies);
!> - immersed_diagnostics: status changes, load jumps, divergence and fallback rows for the log.
!>
!> For rigid bodies with a given velocity U and angular velocity Omega about the centre c, the rigid
!> velocity at a point x is u_rigid(x) = U + Omega x r, r = minimum image of x - c. Interior nodes
!> take u_rigid at the node; a ghost node G with surface point B, image point M = B + d_M n and
!> kappa = d_G/d_M takes the row
!>     (1 + kappa w_G) u_G = (1 + kappa) u_B - kappa sum_{j /= G} w_j u_j,   u_B = u_rigid(B)
!> (u_G = 2 u_B - u_M for the pure mirror kappa = 1; Mark & van Wachem 2008), u_M = sum_j w_j u_j
!> trilinear on the component's own grid. A saturated row (two bodies closer than a cell) takes the
!> Couette value across the gap instead (immersed_geometry; docs/theory.md).
module immersed_boundary
  use, intrinsic :: iso_fortran_env, only: int64
  use agglo_kinds, only: wp
  use immersed_geometry, only: immersed_body_t, immersed_geometry_t
  use immersed_ghost_exchange, only: ghost_planes_t
  implicit none
  private
  public :: immersed_boundary_t, ibm_settings_t, imposition_report_t, status_change_report_t, ghost_rows_t

  !> The rigid velocity at a node and the velocity a ghost row is built on (u_B, or the saturated
  !> Couette value): for the imposition and for a solver that imposes the body rows itself
  public :: rigid_velocity, ghost_surface_value

  !> Lever arms r (minimum image of the point - the body's centre, m) of one component's nodes,
  !> computed once per placement so that an imposition costs only U + Omega x r per node.
  type :: lever_arms_t
    real(wp), allocatable :: interior(:, :)   !< (3, n_interior), at the interior nodes
    real(wp), allocatable :: ghost(:, :)      !< (3, n_ghost), at the ghost nodes G
    real(wp), allocatable :: surface(:, :)    !< (3, n_ghost), at their surface points B
    !> (3, n_ghost), at the other body's surface point B' of a saturated row, from that body's centre (else 0)
    real(wp), allocatable :: opposite(:, :)
  end type lever_arms_t

  !> The ghost rows of one component packed for the Jacobi sweeps (immersed_imposition): the fields
  !> of the ghost records a sweep reads (a quarter of a record's bytes), with the stencil's nodes as
  !> positions in the flattened field or in the copied planes, so that a sweep streams through a
  !> short array rather than the whole records. Packed from the records of one classification.
  type :: ghost_rows_t
    integer :: packed_from = -1                 !< geometry%classifications of the records it holds
    integer, allocatable :: node(:)             !< (n_ghost) position of G in the flattened field
    !> (8, n_ghost) each stencil corner: > 0 position in the flattened field, < 0 minus the position
    !> in the flattened below | above planes of the component (above after below), 0 G itself
    integer, allocatable :: source(:, :)
    real(wp), allocatable :: weight(:, :)       !< (8, n_ghost) trilinear weights, as in the records
    !> (8, n_ghost) the stencil values, gathered by the sweeps: all of them at an imposition's first
    !> sweep, then only the corners at ghost nodes whose value changed (the others keep their values)
    real(wp), allocatable :: values(:, :)
    integer :: n_moving = 0                     !< the corners at ghost nodes
    !> (2, n_moving) corner and row of each, grouped by the local ghost row they read (reader_start),
    !> then those read from the copied planes (or without a row of this rank), re-read every sweep
    integer, allocatable :: moving(:, :)
    !> (n_ghost + 1) moving(:, reader_start(r) : reader_start(r + 1) - 1) read ghost row r of this
    !> rank; moving(:, reader_start(n_ghost + 1) : n_moving) the others
    integer, allocatable :: reader_start(:)
    !> (n_ghost) the rows whose value changed in the last sweep: changed(1:n_changed). A row none of
    !> whose ghost corners changed would give the same value again, so a sweep after the first
    !> evaluates only the readers of these rows (and of the copied planes' values that changed).
    integer :: n_changed = 0
    integer, allocatable :: changed(:)
    integer, allocatable :: active(:)           !< (n_ghost) scratch: the rows a sweep evaluates
    logical, allocatable :: is_active(:)        !< (n_ghost) scratch: row in active(:), false between sweeps
    real(wp), allocatable :: kappa(:)           !< (n_ghost) the records' extrapolation
    real(wp), allocatable :: self_weight(:)     !< (n_ghost) the weight of G's own corner (0 if none)
  end type ghost_rows_t

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
    type(ghost_planes_t) :: planes       !< the neighbours' planes the stencils read, and the sweeps' traffic
    type(lever_arms_t) :: arms(3)        !< per component, for the current placement
    type(ghost_rows_t) :: rows(3)        !< per component, the ghost rows packed for the sweeps
    real(wp), allocatable :: arm_centres(:, :)   !< (3, n) the centres the lever arms were computed for
    type(status_change_report_t) :: changes      !< status changes and load jumps (moving bodies)
    real(wp), allocatable :: force_history(:, :, :)   !< (3, n, 2) N, the forces of the last two steps
    !> Work fields of ibm_extend_pressure (field layout, halos): 1 where the cell has a fluid face,
    !> and the values a cell offers to the cell below (above) it by linear extrapolation
    real(wp), allocatable :: cell_open(:, :, :), offer_down(:, :, :), offer_up(:, :, :)
  end type immersed_boundary_t

contains

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
end module immersed_boundary
