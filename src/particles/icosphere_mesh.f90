!> Triangulated spheroid surface for the immersed boundary and for surface integrals of loads
!> (Eqs. 8-10 of the paper): an icosphere (regular icosahedron, each triangle split into four with
!> the edge midpoints pushed onto the unit sphere, `level` times: 20 * 4**level faces; level 2 =
!> 320 faces is the paper's mesh) scaled by (a, b, b) onto the spheroid, as the paper's Blender
!> procedure does (section 2.2.1). Everything is stored in the body frame (metres); rotate with R(q)
!> and translate to use it in the lab frame. Exact geometry (gap, curvature, mass, inertia) never
!> comes from this mesh: the mesh volume is smaller than the spheroid's (3.4% at 320 faces).
module icosphere_mesh
  use agglo_kinds, only: wp
  use vector_algebra, only: cross
  use spheroid, only: spheroid_t
  use error_handling, only: fatal
  implicit none
  private
  public :: icosphere_mesh_t, build_icosphere_mesh, mesh_volume, mesh_area, icosphere_face_count, &
            max_icosphere_level

  integer, parameter :: max_icosphere_level = 4   !< 5120 faces

  type :: icosphere_mesh_t
    integer :: level = -1
    integer :: n_vertices = 0
    integer :: n_faces = 0
    real(wp), allocatable :: vertices(:,:)       !< (3, n_vertices) m, body frame, on the spheroid surface
    integer, allocatable :: faces(:,:)           !< (3, n_faces) vertex indices, counter-clockwise seen from outside
    real(wp), allocatable :: face_centres(:,:)   !< (3, n_faces) m, centroids (inside the true surface)
    real(wp), allocatable :: face_normals(:,:)   !< (3, n_faces) unit outward normals of the flat faces
    real(wp), allocatable :: face_areas(:)       !< (n_faces) m^2
  end type icosphere_mesh_t

contains

  !> Number of faces of the icosphere at subdivision level: 20 * 4**level.
  pure integer function icosphere_face_count(level)
    integer, intent(in) :: level
    icosphere_face_count = 20 * 4**level
  end function icosphere_face_count

  !> Mesh of body at subdivision level 0..4 (20/80/320/1280/5120 faces).
  subroutine build_icosphere_mesh(body, level, mesh)
    type(spheroid_t), intent(in) :: body
    integer, intent(in) :: level
    type(icosphere_mesh_t), intent(out) :: mesh
    real(wp), allocatable :: unit_vertices(:,:)
    integer, allocatable :: faces(:,:)
    integer :: n_vertices, n_faces, l, f
    real(wp) :: edge1(3), edge2(3), normal(3)
    character(len=16) :: text

    if (level < 0 .or. level > max_icosphere_level) then
      write(text, '(i0)') level
      call fatal('icosphere_mesh: subdivision level '//trim(text)//' outside 0..4 (20 to 5120 faces)')
    end if
    ! Final sizes: F = 20 * 4^level, V = F/2 + 2 (Euler, closed triangulated sphere).
    allocate(unit_vertices(3, 10 * 4**level + 2), faces(3, 20 * 4**level))
    call icosahedron(unit_vertices, faces, n_vertices, n_faces)
    do l = 1, level
      call subdivide(unit_vertices, faces, n_vertices, n_faces)
    end do

    mesh%level = level
    mesh%n_vertices = n_vertices
    mesh%n_faces = n_faces
    allocate(mesh%vertices(3, n_vertices), mesh%faces(3, n_faces), mesh%face_centres(3, n_faces), &
             mesh%face_normals(3, n_faces), mesh%face_areas(n_faces))
    ! Affine map of the unit sphere onto the spheroid (the paper's scaling of a Blender icosphere).
    mesh%vertices(1, :) = body%a * unit_vertices(1, 1:n_vertices)
    mesh%vertices(2, :) = body%b * unit_vertices(2, 1:n_vertices)
    mesh%vertices(3, :) = body%b * unit_vertices(3, 1:n_vertices)
    mesh%faces = faces(:, 1:n_faces)
    do f = 1, n_faces
      associate (p1 => mesh%vertices(:, mesh%faces(1, f)), p2 => mesh%vertices(:, mesh%faces(2, f)), &
                 p3 => mesh%vertices(:, mesh%faces(3, f)))
        edge1 = p2 - p1
        edge2 = p3 - p1
        normal = cross(edge1, edge2)
        mesh%face_centres(:, f) = (p1 + p2 + p3) / 3.0_wp
      end associate
      ! The body is convex and contains its centre, so an outward face has normal . centroid > 0;
      ! orient every face that way (counter-clockwise from outside).
      if (dot_product(normal, mesh%face_centres(:, f)) < 0.0_wp) then
        mesh%faces(2:3, f) = mesh%faces([3, 2], f)
        normal = -normal
      end if
      mesh%face_areas(f) = 0.5_wp * norm2(normal)
      mesh%face_normals(:, f) = normal / norm2(normal)
    end do
  end subroutine build_icosphere_mesh

  !> Enclosed volume of the closed mesh (divergence theorem: sum of signed tetrahedra from the origin).
  pure function mesh_volume(mesh) result(volume)
    type(icosphere_mesh_t), intent(in) :: mesh
    real(wp) :: volume
    integer :: f
    volume = 0.0_wp
    do f = 1, mesh%n_faces
      volume = volume + dot_product(mesh%vertices(:, mesh%faces(1, f)), &
                                    cross(mesh%vertices(:, mesh%faces(2, f)), mesh%vertices(:, mesh%faces(3, f))))
    end do
    volume = volume / 6.0_wp
  end function mesh_volume

  pure function mesh_area(mesh) result(area)
    type(icosphere_mesh_t), intent(in) :: mesh
    real(wp) :: area
    area = sum(mesh%face_areas)
  end function mesh_area

  !> Regular icosahedron inscribed in the unit sphere: the 12 vertices are the cyclic permutations
  !> of (0, +-1, +-g), g the golden ratio, normalised; 20 faces (orientation fixed later).
  subroutine icosahedron(vertices, faces, n_vertices, n_faces)
    real(wp), intent(inout) :: vertices(:,:)
    integer, intent(inout) :: faces(:,:)
    integer, intent(out) :: n_vertices, n_faces
    real(wp) :: g
    integer :: i
    g = 0.5_wp * (1.0_wp + sqrt(5.0_wp))
    vertices(:, 1:12) = reshape([ -1.0_wp, g, 0.0_wp,   1.0_wp, g, 0.0_wp,   -1.0_wp, -g, 0.0_wp,   1.0_wp, -g, 0.0_wp, &
                                  0.0_wp, -1.0_wp, g,   0.0_wp, 1.0_wp, g,   0.0_wp, -1.0_wp, -g,   0.0_wp, 1.0_wp, -g, &
                                  g, 0.0_wp, -1.0_wp,   g, 0.0_wp, 1.0_wp,   -g, 0.0_wp, -1.0_wp,   -g, 0.0_wp, 1.0_wp], [3, 12])
    do i = 1, 12
      vertices(:, i) = vertices(:, i) / norm2(vertices(:, i))
    end do
    ! Each face is a triple of mutually adjacent vertices (edge length 2 before normalisation).
    faces(:, 1:20) = reshape([1, 12, 6,   1, 6, 2,   1, 2, 8,   1, 8, 11,   1, 11, 12, &
                              2, 6, 10,   6, 12, 5,   12, 11, 3,   11, 8, 7,   8, 2, 9, &
                              4, 10, 5,   4, 5, 3,   4, 3, 7,   4, 7, 9,   4, 9, 10, &
                              5, 10, 6,   3, 5, 12,   7, 3, 11,   9, 7, 8,   10, 9, 2], [3, 20])
    n_vertices = 12
    n_faces = 20
  end subroutine icosahedron

  !> One subdivision: each triangle into four through its edge midpoints, which are projected onto
  !> the unit sphere. Midpoints are shared between the two faces of an edge (looked up in a small
  !> per-vertex edge table: every vertex of an icosphere has 5 or 6 neighbours).
  subroutine subdivide(vertices, faces, n_vertices, n_faces)
    real(wp), intent(inout) :: vertices(:,:)
    integer, intent(inout) :: faces(:,:)
    integer, intent(inout) :: n_vertices, n_faces
    integer, allocatable :: old_faces(:,:), edge_end(:,:), edge_mid(:,:), edge_count(:)
    integer :: f, n_old, m(3), k, c(3)
    n_old = n_faces
    allocate(old_faces(3, n_old), edge_end(6, n_vertices), edge_mid(6, n_vertices), edge_count(n_vertices))
    old_faces = faces(:, 1:n_old)
    edge_count = 0
    n_faces = 0
    do f = 1, n_old
      c = old_faces(:, f)
      do k = 1, 3
        m(k) = midpoint(c(k), c(mod(k, 3) + 1))
      end do
      call add_face(c(1), m(1), m(3))
      call add_face(c(2), m(2), m(1))
      call add_face(c(3), m(3), m(2))
      call add_face(m(1), m(2), m(3))
    end do
  contains
    integer function midpoint(i, j)
      integer, intent(in) :: i, j
      integer :: low, high, e
      low = min(i, j)
      high = max(i, j)
      do e = 1, edge_count(low)
        if (edge_end(e, low) == high) then
          midpoint = edge_mid(e, low)
          return
        end if
      end do
      n_vertices = n_vertices + 1
      vertices(:, n_vertices) = vertices(:, i) + vertices(:, j)
      vertices(:, n_vertices) = vertices(:, n_vertices) / norm2(vertices(:, n_vertices))
      edge_count(low) = edge_count(low) + 1
      edge_end(edge_count(low), low) = high
      edge_mid(edge_count(low), low) = n_vertices
      midpoint = n_vertices
    end function midpoint
    subroutine add_face(i, j, k)
      integer, intent(in) :: i, j, k
      n_faces = n_faces + 1
      faces(:, n_faces) = [i, j, k]
    end subroutine add_face
  end subroutine subdivide

end module icosphere_mesh
