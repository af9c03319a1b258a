!> Attributes of the files of hdf5_files: small values attached to the root group (or any group or
!> dataset) of a file, for the identity of a file that a reader checks before its datasets
!> (h5py: f.attrs[name]). Written by every rank that has the file open with the same values (a
!> serial file: its one rank); an existing attribute of the same name is replaced.
!>   h5_write_attribute(file, object, name, value)  value: integer scalar, real(wp) vector, text,
!>                                                  or an array of texts (fixed length, NUL-padded)
module hdf5_attributes
  use, intrinsic :: iso_c_binding, only: c_char, c_null_char, c_loc
  use hdf5, only: hid_t, hsize_t, size_t, h5oopen_f, h5oclose_f, h5aexists_f, h5adelete_f, h5acreate_f, h5awrite_f, &
                  h5aclose_f, h5screate_f, h5screate_simple_f, h5sclose_f, H5S_SCALAR_F, h5tcopy_f, h5tclose_f, &
                  h5tset_size_f, h5tset_strpad_f, H5T_FORTRAN_S1, H5T_STR_NULLPAD_F, H5T_NATIVE_INTEGER, &
                  H5T_NATIVE_DOUBLE
  use agglo_kinds, only: wp
  use hdf5_files, only: h5_file_t, require_ok, require_open
  implicit none
  private
  public :: h5_write_attribute

  interface h5_write_attribute
    module procedure write_int_attribute, write_real_attribute, write_text_attribute, write_texts_attribute
  end interface h5_write_attribute

contains

  !> Open object (a group or dataset path, '/' for the root) and make attribute name of the given
  !> type and shape (dims empty: scalar), replacing one that exists.
  subroutine create_attribute(file, object, name, type_id, dims, object_id, attribute)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: object, name
    integer(hid_t), intent(in) :: type_id
    integer(hsize_t), intent(in) :: dims(:)
    integer(hid_t), intent(out) :: object_id, attribute
    integer(hid_t) :: space
    logical :: exists
    integer :: status
    call require_open(file, object//'@'//name, .true.)
    call h5oopen_f(file%id, object, object_id, status)
    call require_ok(status, 'opening the object of an attribute', file, object)
    call h5aexists_f(object_id, name, exists, status)
    if (exists) call h5adelete_f(object_id, name, status)
    if (size(dims) == 0) then
      call h5screate_f(H5S_SCALAR_F, space, status)
    else
      call h5screate_simple_f(size(dims), dims, space, status)
    end if
    call h5acreate_f(object_id, name, type_id, space, attribute, status)
    call require_ok(status, 'creating an attribute', file, object//'@'//name)
    call h5sclose_f(space, status)
  end subroutine create_attribute

  subroutine close_attribute(object_id, attribute)
    integer(hid_t), intent(in) :: object_id, attribute
    integer :: status
    call h5aclose_f(attribute, status)
    call h5oclose_f(object_id, status)
  end subroutine close_attribute

  subroutine write_int_attribute(file, object, name, value)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: object, name
    integer, intent(in), target :: value
    integer(hid_t) :: object_id, attribute
    integer :: status
    call create_attribute(file, object, name, H5T_NATIVE_INTEGER, [integer(hsize_t) ::], object_id, attribute)
    call h5awrite_f(attribute, H5T_NATIVE_INTEGER, c_loc(value), status)
    call require_ok(status, 'writing an attribute', file, object//'@'//name)
    call close_attribute(object_id, attribute)
  end subroutine write_int_attribute

  subroutine write_real_attribute(file, object, name, values)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: object, name
    real(wp), intent(in), target :: values(:)
    integer(hid_t) :: object_id, attribute
    integer :: status
    call create_attribute(file, object, name, H5T_NATIVE_DOUBLE, [int(size(values), hsize_t)], object_id, attribute)
    call h5awrite_f(attribute, H5T_NATIVE_DOUBLE, c_loc(values), status)
    call require_ok(status, 'writing an attribute', file, object//'@'//name)
    call close_attribute(object_id, attribute)
  end subroutine write_real_attribute

  !> A text: one fixed-length string (h5py: f.attrs[name].decode()).
  subroutine write_text_attribute(file, object, name, text)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: object, name, text
    call write_strings(file, object, name, [text], scalar=.true.)
  end subroutine write_text_attribute

  !> Texts: an array of fixed-length strings as long as the longest, NUL-padded.
  subroutine write_texts_attribute(file, object, name, texts)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: object, name
    character(len=*), intent(in) :: texts(:)
    call write_strings(file, object, name, texts, scalar=.false.)
  end subroutine write_texts_attribute

  subroutine write_strings(file, object, name, texts, scalar)
    type(h5_file_t), intent(in) :: file
    character(len=*), intent(in) :: object, name
    character(len=*), intent(in) :: texts(:)
    logical, intent(in) :: scalar
    character(kind=c_char, len=:), allocatable, target :: buffer
    integer(hid_t) :: string_type, object_id, attribute
    integer :: status, length, i
    ! An HDF5 string type cannot have length 0: empty texts are stored as one NUL.
    length = 1
    do i = 1, size(texts)
      length = max(length, len_trim(texts(i)))
    end do
    allocate(character(kind=c_char, len=length * max(size(texts), 1)) :: buffer)
    buffer = repeat(c_null_char, len(buffer))
    do i = 1, size(texts)
      buffer((i - 1) * length + 1:(i - 1) * length + len_trim(texts(i))) = trim(texts(i))
    end do
    call h5tcopy_f(H5T_FORTRAN_S1, string_type, status)
    call h5tset_size_f(string_type, int(length, size_t), status)
    call h5tset_strpad_f(string_type, H5T_STR_NULLPAD_F, status)
    call require_ok(status, 'making a string type', file, object//'@'//name)
    if (scalar) then
      call create_attribute(file, object, name, string_type, [integer(hsize_t) ::], object_id, attribute)
    else
      call create_attribute(file, object, name, string_type, [int(size(texts), hsize_t)], object_id, attribute)
    end if
    call h5awrite_f(attribute, string_type, c_loc(buffer), status)
    call require_ok(status, 'writing an attribute', file, object//'@'//name)
    call close_attribute(object_id, attribute)
    call h5tclose_f(string_type, status)
  end subroutine write_strings
end module hdf5_attributes
