//! numpy's `.npz`: a zip archive of `.npy` arrays, stored uncompressed.
//!
//! Each array is an `.npy` file of format version 1.0: the magic `\x93NUMPY`, the version
//! bytes `1 0`, a little-endian `u16` header length, then the header, a Python dict literal
//! `{'descr': …, 'fortran_order': False, 'shape': (…), }` padded with spaces to end in a newline
//! at a multiple of 64 bytes, then the data in C order. Numbers are little-endian `float64`
//! (`<f8`), flags are `|b1` (one byte, 0 or 1), strings are `<U{n}` (UTF-32LE code points,
//! zero-padded to the longest string's `n`).
//!
//! The archive holds one entry `NAME.npy` per array: a local header (method 0, stored), the
//! bytes, then the central directory and its end record, with the CRC-32 (IEEE 802.3,
//! reflected, polynomial `0xEDB88320`) of each entry. No zip64: an entry or the archive over
//! 4 GiB is refused (a 120 Hz hour of a 29-joint robot is 0.1 GB).

use std::io::Write;

use super::motion::{ExportError, MotionTrack};

/// One array of an `.npz`, borrowed.
#[derive(Debug, Clone, Copy)]
pub enum NpyArray<'a> {
    /// `float64` numbers of the given shape (C order; `&[]` is a scalar).
    F64 {
        /// The array's shape.
        shape: &'a [usize],
        /// Its values, `shape.iter().product()` of them.
        data: &'a [f64],
    },
    /// Flags of the given shape.
    Bool {
        /// The array's shape.
        shape: &'a [usize],
        /// Its values.
        data: &'a [bool],
    },
    /// A one-dimensional array of strings.
    Str(&'a [String]),
}

impl NpyArray<'_> {
    /// The `.npy` file of this array.
    fn to_npy(self) -> Result<Vec<u8>, ExportError> {
        let (descr, shape, body): (String, Vec<usize>, Vec<u8>) = match self {
            NpyArray::F64 { shape, data } => {
                check_len(shape, data.len())?;
                let body = data.iter().flat_map(|v| v.to_le_bytes()).collect();
                ("<f8".into(), shape.to_vec(), body)
            }
            NpyArray::Bool { shape, data } => {
                check_len(shape, data.len())?;
                (
                    "|b1".into(),
                    shape.to_vec(),
                    data.iter().map(|&b| u8::from(b)).collect(),
                )
            }
            NpyArray::Str(strings) => {
                let width = strings
                    .iter()
                    .map(|s| s.chars().count())
                    .max()
                    .unwrap_or(0)
                    .max(1);
                let mut body = Vec::with_capacity(strings.len() * width * 4);
                for s in strings {
                    let n = s.chars().count();
                    body.extend(s.chars().flat_map(|c| u32::from(c).to_le_bytes()));
                    body.extend(std::iter::repeat_n(0u8, (width - n) * 4));
                }
                (format!("<U{width}"), vec![strings.len()], body)
            }
        };
        let shape = match shape.as_slice() {
            [] => "()".to_owned(),
            [n] => format!("({n},)"),
            dims => format!(
                "({})",
                dims.iter()
                    .map(usize::to_string)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        };
        let mut header =
            format!("{{'descr': '{descr}', 'fortran_order': False, 'shape': {shape}, }}");
        let unpadded = MAGIC.len() + 2 + 2 + header.len() + 1;
        header.extend(std::iter::repeat_n(
            ' ',
            unpadded.next_multiple_of(64) - unpadded,
        ));
        header.push('\n');
        let mut npy = Vec::with_capacity(MAGIC.len() + 4 + header.len() + body.len());
        npy.extend_from_slice(MAGIC);
        npy.extend_from_slice(&[1, 0]);
        npy.extend_from_slice(&(header.len() as u16).to_le_bytes());
        npy.extend_from_slice(header.as_bytes());
        npy.extend_from_slice(&body);
        Ok(npy)
    }
}

const MAGIC: &[u8] = b"\x93NUMPY";

fn check_len(shape: &[usize], len: usize) -> Result<(), ExportError> {
    if shape.iter().product::<usize>() == len {
        Ok(())
    } else {
        Err(ExportError::Io(std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            format!("npy array of shape {shape:?} given {len} values"),
        )))
    }
}

/// Writes the `.npz` archive of `arrays` (name without `.npy`, array) to `out`.
///
/// # Errors
/// [`ExportError::Io`] when writing fails, an array's data does not fill its shape, or the
/// archive would exceed 4 GiB.
pub fn write_npz(mut out: impl Write, arrays: &[(&str, NpyArray<'_>)]) -> Result<(), ExportError> {
    let too_big = || {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "npz over 4 GiB (no zip64)",
        )
    };
    let mut central = Vec::new();
    let mut offset: u32 = 0;
    for (name, array) in arrays {
        let npy = array.to_npy()?;
        let name = format!("{name}.npy");
        let size = u32::try_from(npy.len()).map_err(|_| too_big())?;
        let crc = crc32(&npy);
        let local = entry_header(LOCAL, &name, crc, size, None);
        out.write_all(&local)?;
        out.write_all(&npy)?;
        central.extend(entry_header(CENTRAL, &name, crc, size, Some(offset)));
        let written = local.len() + npy.len();
        offset = u32::try_from(written)
            .ok()
            .and_then(|w| offset.checked_add(w))
            .ok_or_else(too_big)?;
    }
    let count = u16::try_from(arrays.len()).map_err(|_| too_big())?;
    let mut end = Vec::with_capacity(22);
    end.extend_from_slice(&0x0605_4b50u32.to_le_bytes());
    end.extend_from_slice(&[0, 0, 0, 0]); // this disk, the central directory's disk
    end.extend_from_slice(&count.to_le_bytes());
    end.extend_from_slice(&count.to_le_bytes());
    end.extend_from_slice(&(central.len() as u32).to_le_bytes());
    end.extend_from_slice(&offset.to_le_bytes());
    end.extend_from_slice(&[0, 0]); // comment length
    out.write_all(&central)?;
    out.write_all(&end)?;
    Ok(out.flush()?)
}

const LOCAL: u32 = 0x0403_4b50;
const CENTRAL: u32 = 0x0201_4b50;

/// A local file header (`offset` `None`) or a central directory header of a stored entry.
fn entry_header(signature: u32, name: &str, crc: u32, size: u32, offset: Option<u32>) -> Vec<u8> {
    const VERSION: u16 = 20; // 2.0: what a stored entry needs
    const DOS_DATE: u16 = (1 << 5) | 1; // 1980-01-01, the earliest a zip can say
    let mut h = Vec::with_capacity(46 + name.len());
    h.extend_from_slice(&signature.to_le_bytes());
    if offset.is_some() {
        h.extend_from_slice(&VERSION.to_le_bytes()); // version made by
    }
    for field in [VERSION, 0, 0, 0, DOS_DATE] {
        h.extend_from_slice(&field.to_le_bytes()); // needed, flags, method, time, date
    }
    for field in [crc, size, size] {
        h.extend_from_slice(&field.to_le_bytes());
    }
    h.extend_from_slice(&(name.len() as u16).to_le_bytes());
    h.extend_from_slice(&[0, 0]); // extra field length
    if let Some(offset) = offset {
        h.extend_from_slice(&[0; 8]); // comment length, disk, internal and external attributes
        h.extend_from_slice(&[0; 2]);
        h.extend_from_slice(&offset.to_le_bytes());
    }
    h.extend_from_slice(name.as_bytes());
    h
}

/// CRC-32 of `bytes` (zip's: reflected, polynomial `0xEDB88320`, initial and final XOR
/// `0xFFFFFFFF`).
pub(crate) fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = !0u32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            crc = (crc >> 1) ^ (0xEDB8_8320 & (crc & 1).wrapping_neg());
        }
    }
    !crc
}

/// Writes `track` as `motion.npz` to `out`, sampled at `fps` frames a second
/// ([`MotionTrack::resampled`]): `fps` (scalar), `time` (N, s), `joint_names` (J),
/// `dof_pos` (N × J, rad), `root_pos` (N × 3, m, world), `root_quat` (N × 4, x y z w, world),
/// `contacts` (N × 2, left and right sole on the floor).
///
/// # Errors
/// [`ExportError`] for a bad rate, an empty track, or a failed write.
pub fn write_motion_npz(out: impl Write, track: &MotionTrack, fps: f64) -> Result<(), ExportError> {
    let t = track.resampled(fps)?;
    let (n, j) = (t.len(), t.joint_count());
    let flat = |rows: &[[f64; 3]]| rows.iter().flatten().copied().collect::<Vec<_>>();
    let root_pos = flat(&t.root_pos);
    let root_quat: Vec<f64> = t.root_quat.iter().flatten().copied().collect();
    let contacts: Vec<bool> = t.contacts.iter().flatten().copied().collect();
    write_npz(
        out,
        &[
            (
                "fps",
                NpyArray::F64 {
                    shape: &[],
                    data: &[fps],
                },
            ),
            (
                "time",
                NpyArray::F64 {
                    shape: &[n],
                    data: &t.time,
                },
            ),
            ("joint_names", NpyArray::Str(&t.joint_names)),
            (
                "dof_pos",
                NpyArray::F64 {
                    shape: &[n, j],
                    data: &t.dof_pos,
                },
            ),
            (
                "root_pos",
                NpyArray::F64 {
                    shape: &[n, 3],
                    data: &root_pos,
                },
            ),
            (
                "root_quat",
                NpyArray::F64 {
                    shape: &[n, 4],
                    data: &root_quat,
                },
            ),
            (
                "contacts",
                NpyArray::Bool {
                    shape: &[n, 2],
                    data: &contacts,
                },
            ),
        ],
    )
}

#[cfg(test)]
mod tests {
    #[test]
    fn crc32_gives_the_check_values_of_the_zip_crc() {
        // The CRC-32 catalogue's check value of "123456789", and the empty input.
        assert_eq!(super::crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(super::crc32(b""), 0);
        assert_eq!(
            super::crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
    }
}
