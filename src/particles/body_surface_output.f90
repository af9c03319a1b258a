!> The bodies' surfaces in the field snapshots, so ParaView shows them in the flow: each body's
!> icosphere mesh (icosphere_mesh: the unit icosphere of a level mapped onto the spheroid) posed at
!> its centre and orientation, written as a triangulated surface body_<n> of the snapshot
!> (field_output: /surfaces/body_<n>/vertices and faces, a Triangle grid in fields.xdmf), with the
!> pose it was drawn at:
!>   /surfaces/body_<n>/centre       (3)  m, lab frame, wrapped into the box [0, L)
!>   /surfaces/body_<n>/orientation  (4)  quaternion body -> lab, scalar first
!>   /surfaces/body_<n>/semi_axes    (2)  m, a (symmetry axis, body x) and b (body y, z)
!>   /surfaces/body_<n>/cluster      (n_faces) integer, the body's cluster (poses with cluster > 0:
!>                                   a suspension's agglomerates), a Cell attribute in fields.xdmf
!> vertex = centre + R(q) (a x, b y, b z) for the unit icosphere's vertex (x, y, z), so every vertex
!> lies on the spheroid surface of that pose. A body that crosses the box faces is drawn whole at
!> its wrapped centre (its periodic image is not drawn). Any scene calls it with a list of poses.
module body_surface_output
  use agglo_kinds, only: wp
  use error_handling, only: fatal
  use text_format, only: int_text
  use hdf5_datasets, only: h5_write_array
  use spheroid, only: spheroid_t
  use quaternion, only: rotation_matrix
  use icosphere_mesh, only: icosphere_mesh_t, build_icosphere_mesh
  use field_output, only: field_snapshot_t, field_snapshot_add_surface, field_snapshot_add_surface_values
  use particle_system, only: particle_system_t
  implicit none
  private
  public :: body_pose_t, field_snapshot_add_bodies, body_surface_level, system_body_poses

  !> Icosphere level of the drawn surfaces: 1280 faces, 642 vertices per body (smooth in ParaView,
  !> about 31 kB per body and snapshot).
  integer, parameter :: body_surface_level = 3

  !> What is needed to draw one body: its shape and its pose.
  type :: body_pose_t
    type(spheroid_t) :: shape
    real(wp) :: centre(3) = 0                                       !< m, lab frame
    real(wp) :: orientation(4) = [1.0_wp, 0.0_wp, 0.0_wp, 0.0_wp]   !< body -> lab, scalar first
    integer :: cluster = 0                                          !< agglomerate number; 0 = none drawn
  end type body_pose_t

contains

  !> Add every body's posed surface to an open snapshot (collective, between field_snapshot_begin
  !> and field_snapshot_end; every rank passes the same poses). box: the periods (m) the centres are
  !> wrapped into. level: icosphere level (default body_surface_level).
  subroutine field_snapshot_add_bodies(snapshot, bodies, box, level)
    type(field_snapshot_t), intent(inout) :: snapshot
    type(body_pose_t), intent(in) :: bodies(:)
    real(wp), intent(in) :: box(3)
    integer, intent(in), optional :: level
    type(icosphere_mesh_t) :: mesh
    real(wp), allocatable :: vertices(:,:)
    real(wp) :: rotation(3, 3), centre(3)
    character(len=:), allocatable :: name
    integer :: n, v, mesh_level
    mesh_level = body_surface_level
    if (present(level)) mesh_level = level
    if (any(.not. box > 0.0_wp)) call fatal('body_surface_output: the box lengths must be positive')
    do n = 1, size(bodies)
      if (.not. (bodies(n)%shape%a > 0.0_wp .and. bodies(n)%shape%b > 0.0_wp)) &
        call fatal('body_surface_output: body '//int_text(n)//' has no positive semi-axes')
      call build_icosphere_mesh(bodies(n)%shape, mesh_level, mesh)
      rotation = rotation_matrix(bodies(n)%orientation)
      centre = modulo(bodies(n)%centre, box)
      allocate(vertices(3, mesh%n_vertices))
      do v = 1, mesh%n_vertices
        vertices(:, v) = centre + matmul(rotation, mesh%vertices(:, v))
      end do
      name = 'body_'//int_text(n)
      call field_snapshot_add_surface(snapshot, name, vertices, mesh%faces)
      call h5_write_array(snapshot%file, 'surfaces/'//name//'/centre', centre)
      call h5_write_array(snapshot%file, 'surfaces/'//name//'/orientation', bodies(n)%orientation)
      call h5_write_array(snapshot%file, 'surfaces/'//name//'/semi_axes', [bodies(n)%shape%a, bodies(n)%shape%b])
      if (bodies(n)%cluster > 0) call field_snapshot_add_surface_values(snapshot, name, 'cluster', &
                                                                        spread(bodies(n)%cluster, 1, size(mesh%faces, 2)))
      deallocate(vertices)
    end do
  end subroutine field_snapshot_add_bodies

  !> The poses of a particle system's bodies (the free bodies of the pair scenes).
  function system_body_poses(system) result(bodies)
    type(particle_system_t), intent(in) :: system
    type(body_pose_t), allocatable :: bodies(:)
    integer :: n
    allocate(bodies(system%n))
    do n = 1, system%n
      bodies(n)%shape = system%shapes(n)
      bodies(n)%centre = system%bodies(n)%position
      bodies(n)%orientation = system%bodies(n)%quaternion
    end do
  end function system_body_poses
end module body_surface_output
