!> Field snapshots: one HDF5 file per output time, fields_<step, 10 digits>.h5 in the run directory,
!> written collectively from the z-decomposed fields, and the XDMF 3 sidecar fields.xdmf (a temporal
!> collection of every snapshot so far) that ParaView and VisIt open.
!>
!> Snapshot file layout (Fortran shapes; h5py shows them reversed):
!>   /fields/<name>   (nx, ny, nz) real(wp)  interior values of each field
!>   /time            scalar, s             /step  scalar integer(i8)
!>   /grid/shape      (3) integer           /grid/lengths (3) m, box lx, ly, lz
!>   /field_names, /field_locations  strings, blank-separated, one word per field
!> A snapshot is written to fields_<step>.h5.tmp and renamed when complete (a killed run never leaves
!> a torn snapshot behind); fields.xdmf is then rebuilt (also via a temporary name) from the complete
!> snapshot files in the directory, so it stays right across restarts. Snapshots of steps after the
!> current one (left by a killed run that went past its last checkpoint) are left out; the continued
!> run overwrites them when it gets there.
!>
!> Staggered fields in XDMF (MAC grid, layout of fluid_grid): every field is written as
!> NODE data of a 3DCoRectMesh whose nodes are exactly the points where that field lives:
!>   location 'centre' (pressure, scalars): nodes at ((i-1/2)dx, (j-1/2)dy, (k-1/2)dz), origin (dx/2, dy/2, dz/2)
!>   location 'x_face' (u):                 nodes at (i dx, (j-1/2)dy, (k-1/2)dz),       origin (dx, dy/2, dz/2)
!>   location 'y_face' (v):                 origin (dx/2, dy, dz/2)
!>   location 'z_face' (w):                 origin (dx/2, dy/2, dz)
!> all with spacing (dx, dy, dz) and nx x ny x nz nodes. Each snapshot is therefore a spatial
!> collection of up to four uniform grids (one per location in use): no value is moved by the
!> half-cell shifts that a single cell-centred grid would impose on u, v, w. To combine the velocity
!> components in ParaView, resample them onto one grid (e.g. "Resample With Dataset").
!> XDMF lists Dimensions and the ORIGIN_DXDYDZ origin and spacing slowest index first: (z, y, x).
!>
!> Triangulated surfaces (the bodies' meshes, body_surface_output) may go into the same snapshot:
!>   /surfaces/<name>/vertices (3, n_vertices) real(wp), m, lab frame
!>   /surfaces/<name>/faces    (3, n_faces) integer, ZERO-based vertex indices (XDMF's convention)
!>   /surface_names            string, blank-separated
!> and each one becomes a Triangle grid of that time's spatial collection in fields.xdmf, so the
!> surfaces share the snapshots' times, files and fate on restart (discard_snapshots_after).
!> A surface may carry integer values per face (field_snapshot_add_surface_values, e.g. the cluster
!> of a body): /surfaces/<name>/<value name> (n_faces), the value names listed in
!> /surface_value_names (blank-separated), each a Cell attribute of its Triangle grid in fields.xdmf.
module field_output
  use agglo_kinds, only: wp, i8
  use error_handling, only: fatal
  use text_format, only: real_text => exact_real_text, int_text
  use file_system, only: rename_file, remove_path
  use parallel_env, only: is_root, barrier
  use run_directory, only: run_directory_path, run_file, record_run_file, forget_run_file
  use logger, only: log_line
  use directory_listing, only: list_directory, name_length
  use hdf5_files, only: h5_file_t, h5_create, h5_open, h5_close, h5_exists
  use hdf5_datasets, only: h5_read_scalar, h5_write_slab, h5_write_array, h5_read_array, h5_write_string, h5_read_string, &
                           h5_dataset_shape
  implicit none
  private
  public :: field_snapshot_t, field_snapshot_begin, field_snapshot_add, field_snapshot_end, write_field_snapshot, &
            field_snapshot_name, discard_snapshots_after, at_cell_centre, at_x_face, at_y_face, at_z_face, &
            field_snapshot_add_surface, field_snapshot_add_surface_values

  character(len=*), parameter :: at_cell_centre = 'centre'   !< pressure and other cell-centred fields
  character(len=*), parameter :: at_x_face = 'x_face'        !< u
  character(len=*), parameter :: at_y_face = 'y_face'        !< v
  character(len=*), parameter :: at_z_face = 'z_face'        !< w
  character(len=*), parameter :: xdmf_name = 'fields.xdmf'
  integer, parameter :: word_length = 64

  !> A snapshot being written (between field_snapshot_begin and field_snapshot_end).
  type :: field_snapshot_t
    type(h5_file_t) :: file
    integer(i8) :: step = 0_i8
    real(wp) :: time = 0.0_wp
    integer :: global_shape(3) = 0
    real(wp) :: lengths(3) = 0.0_wp
    character(len=:), allocatable :: names, locations   !< blank-separated, in the order added
    character(len=:), allocatable :: surfaces           !< blank-separated names of the triangulated surfaces
    character(len=:), allocatable :: surface_values     !< blank-separated names of the surfaces' face values
    character(len=:), allocatable :: directory
  end type field_snapshot_t

  !> What the XDMF needs to know about one complete snapshot file.
  type :: snapshot_record_t
    character(len=name_length) :: file_name = ''
    integer(i8) :: step = 0_i8
    real(wp) :: time = 0.0_wp
    integer :: global_shape(3) = 0
    real(wp) :: lengths(3) = 0.0_wp
    character(len=:), allocatable :: names, locations
    character(len=:), allocatable :: surfaces             !< blank-separated ('' without surfaces)
    integer, allocatable :: surface_vertices(:), surface_faces(:)   !< counts, one per surface
    character(len=:), allocatable :: surface_values       !< blank-separated names of the face values
    logical, allocatable :: has_values(:,:)               !< (value name, surface): the surface carries it
  end type snapshot_record_t

  !> Start a snapshot (collective): step (integer or integer(i8)), time in s, global shape (nx, ny, nz),
  !> box lengths (lx, ly, lz) in m. directory defaults to the run directory.
  interface field_snapshot_begin
    module procedure snapshot_begin_i8, snapshot_begin_int
  end interface field_snapshot_begin

  !> Whole snapshot in one call from a stack of fields(nx, ny, nz_local, n_fields).
  interface write_field_snapshot
    module procedure write_field_snapshot_i8, write_field_snapshot_int
  end interface write_field_snapshot

contains

  !> fields_<step, 10 digits>.h5
  function field_snapshot_name(step) result(name)
    integer(i8), intent(in) :: step
    character(len=:), allocatable :: name
    character(len=10) :: digits
    if (step < 0_i8 .or. step > 9999999999_i8) call fatal('field_output: step outside 0 .. 9999999999')
    write(digits, '(i10.10)') step
    name = 'fields_'//digits//'.h5'
  end function field_snapshot_name

  subroutine snapshot_begin_i8(snapshot, step, time, global_shape, lengths, directory)
    type(field_snapshot_t), intent(out) :: snapshot
    integer(i8), intent(in) :: step
    real(wp), intent(in) :: time, lengths(3)
    integer, intent(in) :: global_shape(3)
    character(len=*), intent(in), optional :: directory
    snapshot%directory = run_directory_path()
    if (present(directory)) snapshot%directory = trim(directory)
    if (len(snapshot%directory) == 0) call fatal('field_output: no run directory (prepare_run_directory first)')
    if (any(global_shape < 1) .or. any(.not. lengths > 0.0_wp)) &
      call fatal('field_output: a snapshot needs a positive grid shape and box lengths')
    snapshot%step = step
    snapshot%time = time
    snapshot%global_shape = global_shape
    snapshot%lengths = lengths
    snapshot%names = ''
    snapshot%locations = ''
    snapshot%surfaces = ''
    snapshot%surface_values = ''
    if (present(directory)) then
      call h5_create(snapshot%file, snapshot%directory//'/'//field_snapshot_name(step), complete_on_close=.true.)
    else   ! a file of the run: recorded in its manifest
      call h5_create(snapshot%file, run_file(field_snapshot_name(step)), complete_on_close=.true.)
    end if
  end subroutine snapshot_begin_i8

  subroutine snapshot_begin_int(snapshot, step, time, global_shape, lengths, directory)
    type(field_snapshot_t), intent(out) :: snapshot
    integer, intent(in) :: step
    real(wp), intent(in) :: time, lengths(3)
    integer, intent(in) :: global_shape(3)
    character(len=*), intent(in), optional :: directory
    call snapshot_begin_i8(snapshot, int(step, i8), time, global_shape, lengths, directory)
  end subroutine snapshot_begin_int

  !> Add one field (collective): local(nx, ny, nz_local) = this rank's interior values starting at
  !> global plane z_offset + 1; location = at_cell_centre | at_x_face | at_y_face | at_z_face.
  !> name: letters, digits and '_' only (it becomes a dataset and an XDMF attribute name).
  subroutine field_snapshot_add(snapshot, name, local, z_offset, location)
    type(field_snapshot_t), intent(inout) :: snapshot
    character(len=*), intent(in) :: name, location
    real(wp), intent(in) :: local(:,:,:)
    integer, intent(in) :: z_offset
    if (len_trim(name) == 0 .or. len_trim(name) > word_length .or. &
        verify(trim(name), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') /= 0) &
      call fatal('field_output: field name "'//trim(name)//'" must be 1-64 letters, digits or _')
    if (location_origin_index(location) == 0) &
      call fatal('field_output: field '//trim(name)//': location "'//trim(location)// &
                 '" is not one of centre, x_face, y_face, z_face')
    if (index(' '//snapshot%names//' ', ' '//trim(name)//' ') > 0) &
      call fatal('field_output: field '//trim(name)//' added twice to one snapshot')
    call h5_write_slab(snapshot%file, 'fields/'//trim(name), local, z_offset, snapshot%global_shape)
    snapshot%names = trim(adjustl(snapshot%names//' '//trim(name)))
    snapshot%locations = trim(adjustl(snapshot%locations//' '//trim(location)))
  end subroutine field_snapshot_add

  !> Add a triangulated surface (collective; every rank passes the same mesh, rank 0's is written):
  !> vertices(3, n_vertices) in m (lab frame), faces(3, n_faces) 1-based vertex indices (stored
  !> 0-based). name: letters, digits and '_' (a group and an XDMF grid name).
  subroutine field_snapshot_add_surface(snapshot, name, vertices, faces)
    type(field_snapshot_t), intent(inout) :: snapshot
    character(len=*), intent(in) :: name
    real(wp), intent(in) :: vertices(:,:)
    integer, intent(in) :: faces(:,:)
    if (len_trim(name) == 0 .or. len_trim(name) > word_length .or. &
        verify(trim(name), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') /= 0) &
      call fatal('field_output: surface name "'//trim(name)//'" must be 1-64 letters, digits or _')
    if (index(' '//snapshot%surfaces//' ', ' '//trim(name)//' ') > 0) &
      call fatal('field_output: surface '//trim(name)//' added twice to one snapshot')
    if (size(vertices, 1) /= 3 .or. size(faces, 1) /= 3 .or. size(faces, 2) < 1) &
      call fatal('field_output: surface '//trim(name)//' needs vertices(3, n) and faces(3, m), m >= 1')
    if (any(faces < 1) .or. any(faces > size(vertices, 2))) &
      call fatal('field_output: surface '//trim(name)//' has a face with a vertex index outside 1..'// &
                 int_text(size(vertices, 2)))
    call h5_write_array(snapshot%file, 'surfaces/'//trim(name)//'/vertices', vertices)
    call h5_write_array(snapshot%file, 'surfaces/'//trim(name)//'/faces', faces - 1)
    snapshot%surfaces = trim(adjustl(snapshot%surfaces//' '//trim(name)))
  end subroutine field_snapshot_add_surface

  !> Integer values per face of a surface already added (collective; rank 0's written), a Cell
  !> attribute of its grid in fields.xdmf. name: letters, digits and '_'.
  subroutine field_snapshot_add_surface_values(snapshot, surface, name, values)
    type(field_snapshot_t), intent(inout) :: snapshot
    character(len=*), intent(in) :: surface, name
    integer, intent(in) :: values(:)
    if (len_trim(name) == 0 .or. len_trim(name) > word_length .or. &
        verify(trim(name), 'abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_') /= 0) &
      call fatal('field_output: surface value name "'//trim(name)//'" must be 1-64 letters, digits or _')
    if (any(trim(name) == [character(len=8) :: 'vertices', 'faces'])) &
      call fatal('field_output: surface value name "'//trim(name)//'" is taken by the mesh')
    if (index(' '//snapshot%surfaces//' ', ' '//trim(surface)//' ') == 0) &
      call fatal('field_output: surface values '//trim(name)//' for '//trim(surface)//', a surface not added')
    call h5_write_array(snapshot%file, 'surfaces/'//trim(surface)//'/'//trim(name), values)
    if (index(' '//snapshot%surface_values//' ', ' '//trim(name)//' ') == 0) &
      snapshot%surface_values = trim(adjustl(snapshot%surface_values//' '//trim(name)))
  end subroutine field_snapshot_add_surface_values

  !> Finish a snapshot (collective): metadata, close, rename complete, rebuild fields.xdmf.
  subroutine field_snapshot_end(snapshot)
    type(field_snapshot_t), intent(inout) :: snapshot
    call h5_write_array(snapshot%file, 'time', snapshot%time)
    call h5_write_array(snapshot%file, 'step', snapshot%step)
    call h5_write_array(snapshot%file, 'grid/shape', snapshot%global_shape)
    call h5_write_array(snapshot%file, 'grid/lengths', snapshot%lengths)
    call h5_write_array(snapshot%file, 'grid/spacing', snapshot%lengths / real(snapshot%global_shape, wp))
    call h5_write_string(snapshot%file, 'field_names', snapshot%names)
    call h5_write_string(snapshot%file, 'field_locations', snapshot%locations)
    if (len(snapshot%surfaces) > 0) call h5_write_string(snapshot%file, 'surface_names', snapshot%surfaces)
    if (len(snapshot%surface_values) > 0) call h5_write_string(snapshot%file, 'surface_value_names', &
                                                               snapshot%surface_values)
    call h5_close(snapshot%file)   ! renames the .tmp file once every rank has written
    if (is_root()) then
      if (snapshot%directory == run_directory_path()) call record_run_file(xdmf_name)
      call write_xdmf(snapshot%directory, snapshot%step)
    end if
    call barrier()
  end subroutine field_snapshot_end

  !> On restart from the checkpoint of step: delete the run's snapshots of later steps (written by
  !> the interrupted or stopped run, e.g. the field dump of a CFL or NaN stop: not part of the continued
  !> history) and rebuild fields.xdmf without them. Collective.
  subroutine discard_snapshots_after(step)
    integer(i8), intent(in) :: step
    character(len=name_length), allocatable :: names(:)
    character(len=:), allocatable :: directory
    integer(i8) :: snapshot_step
    integer :: i, ios, removed
    logical :: ok
    directory = run_directory_path()
    removed = 0
    if (is_root()) then
      call list_directory(directory, names, ok)
      do i = 1, size(names)
        if (len_trim(names(i)) /= 20 .or. names(i)(1:7) /= 'fields_' .or. names(i)(18:20) /= '.h5') cycle
        if (verify(names(i)(8:17), '0123456789') /= 0) cycle
        read(names(i)(8:17), '(i10)', iostat=ios) snapshot_step
        if (ios /= 0 .or. snapshot_step <= step) cycle
        call remove_path(directory//'/'//trim(names(i)), ok)
        call forget_run_file(trim(names(i)))
        call log_line('restart: '//trim(names(i))//' (written after step '//int_text(step)// &
                      ' by the interrupted run) removed')
        removed = removed + 1
      end do
      if (removed > 0) call write_xdmf(directory, step)
    end if
    call barrier()
  end subroutine discard_snapshots_after

  subroutine write_field_snapshot_i8(names, locations, fields, z_offset, global_shape, lengths, time, step, directory)
    character(len=*), intent(in) :: names(:), locations(:)
    real(wp), intent(in) :: fields(:,:,:,:)
    integer, intent(in) :: z_offset, global_shape(3)
    real(wp), intent(in) :: lengths(3), time
    integer(i8), intent(in) :: step
    character(len=*), intent(in), optional :: directory
    type(field_snapshot_t) :: snapshot
    integer :: n
    if (size(names) /= size(fields, 4) .or. size(locations) /= size(fields, 4)) &
      call fatal('field_output: write_field_snapshot needs one name and one location per field')
    call field_snapshot_begin(snapshot, step, time, global_shape, lengths, directory)
    do n = 1, size(names)
      call field_snapshot_add(snapshot, names(n), fields(:, :, :, n), z_offset, locations(n))
    end do
    call field_snapshot_end(snapshot)
  end subroutine write_field_snapshot_i8

  subroutine write_field_snapshot_int(names, locations, fields, z_offset, global_shape, lengths, time, step, directory)
    character(len=*), intent(in) :: names(:), locations(:)
    real(wp), intent(in) :: fields(:,:,:,:)
    integer, intent(in) :: z_offset, global_shape(3), step
    real(wp), intent(in) :: lengths(3), time
    character(len=*), intent(in), optional :: directory
    call write_field_snapshot_i8(names, locations, fields, z_offset, global_shape, lengths, time, int(step, i8), &
                                 directory)
  end subroutine write_field_snapshot_int

  !> 1 = centre, 2 = x_face, 3 = y_face, 4 = z_face, 0 = unknown.
  integer function location_origin_index(location)
    character(len=*), intent(in) :: location
    select case (trim(location))
    case (at_cell_centre); location_origin_index = 1
    case (at_x_face); location_origin_index = 2
    case (at_y_face); location_origin_index = 3
    case (at_z_face); location_origin_index = 4
    case default; location_origin_index = 0
    end select
  end function location_origin_index

  !> Physical position of the first value (global index 1, 1, 1) of a field at location (MAC grid).
  function location_origin(location, spacing) result(origin)
    character(len=*), intent(in) :: location
    real(wp), intent(in) :: spacing(3)
    real(wp) :: origin(3)
    origin = 0.5_wp * spacing
    select case (location_origin_index(location))
    case (2); origin(1) = spacing(1)
    case (3); origin(2) = spacing(2)
    case (4); origin(3) = spacing(3)
    end select
  end function location_origin

  ! ---------------------------------------------------------------------------------------------
  ! XDMF sidecar (rank 0)
  ! ---------------------------------------------------------------------------------------------

  !> The complete snapshots in directory with step <= last_step, in step order.
  subroutine find_snapshots(directory, last_step, records)
    character(len=*), intent(in) :: directory
    integer(i8), intent(in) :: last_step
    type(snapshot_record_t), allocatable, intent(out) :: records(:)
    character(len=name_length), allocatable :: names(:)
    type(snapshot_record_t) :: swap
    type(h5_file_t) :: file
    integer(i8) :: step
    integer :: i, j, n, ios
    logical :: ok
    call list_directory(directory, names, ok)
    allocate(records(size(names)))
    n = 0
    do i = 1, size(names)
      if (len_trim(names(i)) /= 20 .or. names(i)(1:7) /= 'fields_' .or. names(i)(18:20) /= '.h5') cycle
      if (verify(names(i)(8:17), '0123456789') /= 0) cycle
      read(names(i)(8:17), '(i10)', iostat=ios) step
      if (ios /= 0 .or. step > last_step) cycle
      n = n + 1
      records(n)%file_name = names(i)
      records(n)%step = step
      call h5_open(file, directory//'/'//trim(names(i)), writable=.false., serial=.true.)
      call h5_read_scalar(file, 'time', records(n)%time)
      call read_int3(file, 'grid/shape', records(n)%global_shape)
      call read_real3(file, 'grid/lengths', records(n)%lengths)
      call h5_read_string(file, 'field_names', records(n)%names)
      call h5_read_string(file, 'field_locations', records(n)%locations)
      call read_surface_counts(file, records(n))
      call h5_close(file)
    end do
    records = records(1:n)
    do i = 2, n   ! insertion sort by step (a few hundred snapshots at most)
      swap = records(i)
      j = i - 1
      do while (j >= 1)
        if (records(j)%step <= swap%step) exit
        records(j + 1) = records(j)
        j = j - 1
      end do
      records(j + 1) = swap
    end do
  end subroutine find_snapshots

  !> The names of a snapshot's surfaces and their vertex and face counts (none in older files).
  subroutine read_surface_counts(file, record)
    type(h5_file_t), intent(in) :: file
    type(snapshot_record_t), intent(inout) :: record
    character(len=word_length), allocatable :: names(:), values(:)
    integer :: s, v
    record%surfaces = ''
    record%surface_values = ''
    if (h5_exists(file, 'surface_names')) call h5_read_string(file, 'surface_names', record%surfaces)
    if (h5_exists(file, 'surface_value_names')) call h5_read_string(file, 'surface_value_names', record%surface_values)
    names = words(record%surfaces)
    values = words(record%surface_values)
    allocate(record%surface_vertices(size(names)), record%surface_faces(size(names)), &
             record%has_values(size(values), size(names)))
    do s = 1, size(names)
      record%surface_vertices(s) = second_dimension('surfaces/'//trim(names(s))//'/vertices')
      record%surface_faces(s) = second_dimension('surfaces/'//trim(names(s))//'/faces')
      do v = 1, size(values)
        record%has_values(v, s) = h5_exists(file, 'surfaces/'//trim(names(s))//'/'//trim(values(v)))
      end do
    end do
  contains
    integer function second_dimension(name)
      character(len=*), intent(in) :: name
      integer(i8), allocatable :: dims(:)
      dims = h5_dataset_shape(file, name)
      if (size(dims) /= 2) call fatal('field_output: '//name//' of '//file%path//' is not (3, n)', collective=.false.)
      if (dims(1) /= 3_i8) call fatal('field_output: '//name//' of '//file%path//' is not (3, n)', collective=.false.)
      second_dimension = int(dims(2))
    end function second_dimension
  end subroutine read_surface_counts

  subroutine read_int3(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    integer, intent(out) :: values(3)
    integer, allocatable :: stored(:)
    call h5_read_array(file, name, stored)
    if (size(stored) /= 3) call fatal('field_output: '//name//' of '//file%path//' is not 3 values', collective=.false.)
    values = stored
  end subroutine read_int3

  subroutine read_real3(file, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: name
    real(wp), intent(out) :: values(3)
    real(wp), allocatable :: stored(:)
    call h5_read_array(file, name, stored)
    if (size(stored) /= 3) call fatal('field_output: '//name//' of '//file%path//' is not 3 values', collective=.false.)
    values = stored
  end subroutine read_real3

  !> Rewrite directory/fields.xdmf for the complete snapshots up to last_step.
  subroutine write_xdmf(directory, last_step)
    character(len=*), intent(in) :: directory
    integer(i8), intent(in) :: last_step
    type(snapshot_record_t), allocatable :: records(:)
    character(len=:), allocatable :: path
    integer :: unit, i, ios
    logical :: ok
    call find_snapshots(directory, last_step, records)
    path = directory//'/'//xdmf_name
    open(newunit=unit, file=path//'.tmp', status='replace', action='write', iostat=ios)
    if (ios /= 0) call fatal('field_output: cannot write '//path//'.tmp', collective=.false.)
    write(unit, '(a)') '<?xml version="1.0" ?>'
    write(unit, '(a)') '<!-- Agglo field snapshots. Each field is node data on the grid of the points where it'
    write(unit, '(a)') '     lives (MAC staggering): centre, x_face (u), y_face (v), z_face (w). See docs/outputs.md. -->'
    write(unit, '(a)') '<Xdmf Version="3.0">'
    write(unit, '(a)') '  <Domain>'
    write(unit, '(a)') '    <Grid Name="fields" GridType="Collection" CollectionType="Temporal">'
    do i = 1, size(records)
      call write_xdmf_snapshot(unit, records(i))
    end do
    write(unit, '(a)') '    </Grid>'
    write(unit, '(a)') '  </Domain>'
    write(unit, '(a)') '</Xdmf>'
    close(unit)
    call rename_file(path//'.tmp', path, ok)
    if (.not. ok) call fatal('field_output: cannot rename '//path//'.tmp', collective=.false.)
  end subroutine write_xdmf

  subroutine write_xdmf_snapshot(unit, record)
    integer, intent(in) :: unit
    type(snapshot_record_t), intent(in) :: record
    character(len=*), parameter :: locations(4) = [character(len=6) :: at_cell_centre, at_x_face, at_y_face, at_z_face]
    character(len=word_length), allocatable :: names(:), field_locations(:)
    character(len=80) :: dims
    character(len=32) :: step_text
    real(wp) :: spacing(3), origin(3)
    integer :: l, n
    names = words(record%names)
    field_locations = words(record%locations)
    if (size(names) /= size(field_locations)) call fatal('field_output: '//trim(record%file_name)// &
        ' has different numbers of field names and locations', collective=.false.)
    spacing = record%lengths / real(record%global_shape, wp)
    write(dims, '(i0,1x,i0,1x,i0)') record%global_shape(3), record%global_shape(2), record%global_shape(1)
    write(step_text, '(i10.10)') record%step
    write(unit, '(a)') '      <Grid Name="step_'//trim(step_text)//'" GridType="Collection" CollectionType="Spatial">'
    write(unit, '(a)') '        <Time Value="'//real_text(record%time)//'" />'
    do l = 1, size(locations)
      if (.not. any(field_locations == locations(l))) cycle
      origin = location_origin(locations(l), spacing)
      write(unit, '(a)') '        <Grid Name="'//trim(locations(l))//'" GridType="Uniform">'
      write(unit, '(a)') '          <Topology TopologyType="3DCoRectMesh" Dimensions="'//trim(dims)//'" />'
      write(unit, '(a)') '          <Geometry GeometryType="ORIGIN_DXDYDZ">'
      write(unit, '(a)') '            <DataItem Name="origin" Dimensions="3" NumberType="Float" Precision="8" Format="XML">'// &
                         real_text(origin(3))//' '//real_text(origin(2))//' '//real_text(origin(1))//'</DataItem>'
      write(unit, '(a)') '            <DataItem Name="spacing" Dimensions="3" NumberType="Float" Precision="8" Format="XML">'// &
                         real_text(spacing(3))//' '//real_text(spacing(2))//' '//real_text(spacing(1))//'</DataItem>'
      write(unit, '(a)') '          </Geometry>'
      do n = 1, size(names)
        if (field_locations(n) /= locations(l)) cycle
        write(unit, '(a)') '          <Attribute Name="'//trim(names(n))//'" AttributeType="Scalar" Center="Node">'
        write(unit, '(a)') '            <DataItem Dimensions="'//trim(dims)//'" NumberType="Float" Precision="8" '// &
                           'Format="HDF">'//trim(record%file_name)//':/fields/'//trim(names(n))//'</DataItem>'
        write(unit, '(a)') '          </Attribute>'
      end do
      write(unit, '(a)') '        </Grid>'
    end do
    call write_xdmf_surfaces(unit, record)
    write(unit, '(a)') '      </Grid>'
  end subroutine write_xdmf_snapshot

  !> One Triangle grid per surface of the snapshot (XDMF 3: connectivity 0-based, XYZ vertices).
  subroutine write_xdmf_surfaces(unit, record)
    integer, intent(in) :: unit
    type(snapshot_record_t), intent(in) :: record
    character(len=word_length), allocatable :: names(:), values(:)
    character(len=:), allocatable :: group
    integer :: s, v
    names = words(record%surfaces)
    values = words(record%surface_values)
    do s = 1, size(names)
      group = trim(record%file_name)//':/surfaces/'//trim(names(s))
      write(unit, '(a)') '        <Grid Name="'//trim(names(s))//'" GridType="Uniform">'
      write(unit, '(a)') '          <Topology TopologyType="Triangle" NumberOfElements="'// &
                         int_text(record%surface_faces(s))//'">'
      write(unit, '(a)') '            <DataItem Dimensions="'//int_text(record%surface_faces(s))//' 3" '// &
                         'NumberType="Int" Precision="4" Format="HDF">'//group//'/faces</DataItem>'
      write(unit, '(a)') '          </Topology>'
      write(unit, '(a)') '          <Geometry GeometryType="XYZ">'
      write(unit, '(a)') '            <DataItem Dimensions="'//int_text(record%surface_vertices(s))//' 3" '// &
                         'NumberType="Float" Precision="8" Format="HDF">'//group//'/vertices</DataItem>'
      write(unit, '(a)') '          </Geometry>'
      do v = 1, size(values)
        if (.not. record%has_values(v, s)) cycle
        write(unit, '(a)') '          <Attribute Name="'//trim(values(v))//'" AttributeType="Scalar" Center="Cell">'
        write(unit, '(a)') '            <DataItem Dimensions="'//int_text(record%surface_faces(s))//'" '// &
                           'NumberType="Int" Precision="4" Format="HDF">'//group//'/'//trim(values(v))//'</DataItem>'
        write(unit, '(a)') '          </Attribute>'
      end do
      write(unit, '(a)') '        </Grid>'
    end do
  end subroutine write_xdmf_surfaces

  !> The blank-separated words of text.
  function words(text) result(list)
    character(len=*), intent(in) :: text
    character(len=word_length), allocatable :: list(:)
    integer :: i, first
    allocate(list(0))
    first = 0
    do i = 1, len(text) + 1
      if (i <= len(text)) then
        if (text(i:i) /= ' ') then
          if (first == 0) first = i
          cycle
        end if
      end if
      if (first > 0) then
        list = [character(len=word_length) :: list, text(first:i - 1)]
        first = 0
      end if
    end do
  end function words
end module field_output
