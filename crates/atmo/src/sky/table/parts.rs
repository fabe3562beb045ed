//! A table's precompute split across processes or machines: part `K` of `N` computes a
//! contiguous run of the columns of sky (16) (a column is one sun and one altitude), and
//! the merge checks that every part is there, of the same atmosphere and settings, and
//! runs the SVD. Maps depend on their column alone, so the merged table is that of one
//! whole run, byte for byte.
//!
//! Part file (`.atmo-sky-part`), little-endian:
//!
//! | field | type |
//! | --- | --- |
//! | magic | 8 bytes `atmo-skp` |
//! | version | `u32` = 1 |
//! | atmosphere and settings | as in a table file ([`super::SkylightTable::to_bytes`]) |
//! | part K, parts N, first column, columns C | 4 x `u32` |
//! | the maps, column after column, `L*L` x R, G, B | `3 C L^2` x `f32` |
//! | CRC-32 of every byte before it | `u32` |

use std::ops::Range;
use std::path::Path;

use super::file::{
    in_file, open, parse_settings, put_f32, put_settings, put_u32, seal, write_bytes,
};
use super::{matrices, SkylightTable, TableSettings};
use crate::atmosphere::Atmosphere;
use crate::error::{Error, Result};

/// The first bytes of every part file.
pub const MAGIC: &[u8; 8] = b"atmo-skp";

/// The part file version this build writes and reads.
pub const VERSION: u32 = 1;

/// The extension of part files.
pub const EXTENSION: &str = "atmo-sky-part";

/// Most parts a precompute splits into: one column each for the largest tables allowed.
pub const MAX_PARTS: usize = 65_536;

/// One part of a split precompute: its columns' skylight maps, and the atmosphere and
/// settings of the whole table.
#[derive(Debug, Clone, PartialEq)]
pub struct TablePart {
    atmosphere: Atmosphere,
    settings: TableSettings,
    /// This part, from 0, and how many there are.
    part: usize,
    parts: usize,
    /// The maps of [`TablePart::columns`], `L*L` values each.
    maps: Vec<[f32; 3]>,
}

impl TablePart {
    /// The columns of part `part` of `parts` in a table of `total` columns: runs as even
    /// as they can be, in order, covering every column once.
    pub fn columns(total: usize, part: usize, parts: usize) -> Range<usize> {
        total * part / parts..total * (part + 1) / parts
    }

    /// Computes part `part` (from 0) of `parts`; `progress(done, of)` counts its maps.
    pub fn compute(
        atmosphere: &Atmosphere,
        settings: &TableSettings,
        part: usize,
        parts: usize,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Self> {
        settings.validate(atmosphere)?;
        let total = settings.sun_steps * settings.altitude_steps;
        check_split(part, parts, total)?;
        let maps = SkylightTable::skylight_maps(
            atmosphere,
            settings,
            Self::columns(total, part, parts),
            progress,
        )?;
        Ok(TablePart {
            atmosphere: atmosphere.clone(),
            settings: settings.clone(),
            part,
            parts,
            maps,
        })
    }

    /// Whether the part is one of a table of `atmosphere` and `settings`.
    pub fn is_of(&self, atmosphere: &Atmosphere, settings: &TableSettings) -> bool {
        self.atmosphere == *atmosphere && self.settings == *settings
    }

    /// Which part this is (from 0), and of how many.
    pub fn index(&self) -> (usize, usize) {
        (self.part, self.parts)
    }

    /// The conventional file name of part `part` (from 0) of `parts`, counted from 1
    /// as people count, sorting in part order: `part-00001-of-00004.atmo-sky-part`.
    pub fn file_name(part: usize, parts: usize) -> String {
        format!("part-{:05}-of-{parts:05}.{EXTENSION}", part + 1)
    }

    /// The file's bytes.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Vec::with_capacity(self.maps.len() * 12 + 4096);
        w.extend_from_slice(MAGIC);
        put_u32(&mut w, VERSION);
        put_settings(&mut w, &self.atmosphere, &self.settings);
        let total = self.settings.sun_steps * self.settings.altitude_steps;
        let columns = Self::columns(total, self.part, self.parts);
        for v in [self.part, self.parts, columns.start, columns.len()] {
            put_u32(&mut w, v as u32);
        }
        self.maps.iter().flatten().for_each(|&x| put_f32(&mut w, x));
        seal(w)
    }

    /// Writes the part to `path` atomically.
    pub fn write(&self, path: &Path) -> Result<()> {
        write_bytes(path, &self.to_bytes())
    }

    /// Reads and validates a part file.
    pub fn read(path: &Path) -> Result<Self> {
        let bytes = crate::files::read_bounded(path, "table part", crate::files::DATA_LIMIT_BYTES)?;
        Self::from_bytes(&bytes, &path.display().to_string())
    }

    /// Parses and validates the bytes of a part file; `origin` names it in errors.
    pub fn from_bytes(bytes: &[u8], origin: &str) -> Result<Self> {
        let (_, mut r) = open(
            bytes,
            MAGIC,
            VERSION,
            origin,
            "a part of an atmo sky table (it does not start with 'atmo-skp'); make parts \
             with `atmo precompute sky --part K/N`",
        )?;
        let parse = |r: &mut super::file::Reader| -> Result<Self> {
            let (atmosphere, settings) = parse_settings(r, origin)?;
            let total = settings.sun_steps * settings.altitude_steps;
            let part = r.u32("part")? as usize;
            let parts = r.u32("parts")? as usize;
            check_split(part, parts, total)?;
            let (first, count) = (r.u32("first column")? as usize, r.u32("columns")? as usize);
            let columns = Self::columns(total, part, parts);
            if first != columns.start || count != columns.len() {
                return Err(Error::Invalid(format!(
                    "columns {first}..{} where part {} of {parts} holds {columns:?}",
                    first + count,
                    part + 1
                )));
            }
            let values = count * settings.sky.directions.pow(2);
            let maps = (0..values)
                .map(|_| Ok([r.f32("maps")?, r.f32("maps")?, r.f32("maps")?]))
                .collect::<Result<Vec<_>>>()?;
            if r.at != r.bytes_len() {
                return Err(Error::Invalid(format!(
                    "{} unexpected bytes after the maps",
                    r.bytes_len() - r.at
                )));
            }
            Ok(TablePart {
                atmosphere,
                settings,
                part,
                parts,
                maps,
            })
        };
        parse(&mut r).map_err(|e| in_file(e, origin))
    }
}

/// Part `part` of `parts` must exist and hold at least one of `total` columns.
fn check_split(part: usize, parts: usize, total: usize) -> Result<()> {
    if parts == 0 || parts > total.min(MAX_PARTS) {
        return Err(Error::Invalid(format!(
            "{parts} parts of a table of {total} maps: allowed 1 to {} (a map a part at most)",
            total.min(MAX_PARTS)
        )));
    }
    if part >= parts {
        return Err(Error::Invalid(format!(
            "part {} of {parts}: parts are counted from 1 to {parts}",
            part + 1
        )));
    }
    Ok(())
}

impl SkylightTable {
    /// The table from the parts of a split precompute, in any order: each part once, all
    /// of one atmosphere and settings; then the SVD as [`SkylightTable::precompute`].
    pub fn merge(mut parts: Vec<TablePart>) -> Result<Self> {
        let Some(first) = parts.first() else {
            return Err(Error::Invalid("no parts to merge".into()));
        };
        let (atmosphere, settings, n) = (
            first.atmosphere.clone(),
            first.settings.clone(),
            first.parts,
        );
        if let Some(other) = parts
            .iter()
            .find(|p| p.atmosphere != atmosphere || p.settings != settings || p.parts != n)
        {
            return Err(Error::Invalid(format!(
                "part {} of {} was computed with another atmosphere or other settings than \
                 part {} of {n}: merge the parts of one precompute",
                other.part + 1,
                other.parts,
                first.part + 1
            )));
        }
        parts.sort_by_key(|p| p.part);
        if let Some(w) = parts.windows(2).find(|w| w[0].part == w[1].part) {
            return Err(Error::Invalid(format!(
                "part {} of {n} is there twice",
                w[0].part + 1
            )));
        }
        let missing: Vec<String> = (0..n)
            .filter(|k| parts.binary_search_by_key(k, |p| p.part).is_err())
            .map(|k| (k + 1).to_string())
            .collect();
        if !missing.is_empty() {
            return Err(Error::Invalid(format!(
                "parts {} of {n} are missing",
                missing.join(", ")
            )));
        }
        let maps: Vec<[f32; 3]> = parts.into_iter().flat_map(|p| p.maps).collect();
        Self::from_matrices(&atmosphere, &settings, &matrices(&settings, &maps))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sky::SkySettings;

    /// A table small enough to compute in a second: the paper's two orders, coarse.
    fn small() -> (Atmosphere, TableSettings) {
        let settings = TableSettings {
            sky: SkySettings {
                directions: 16,
                ..SkySettings::paper()
            },
            sun_steps: 7,
            altitude_steps: 3,
            ..TableSettings::default()
        };
        (Atmosphere::earth(), settings)
    }

    #[test]
    fn the_parts_cover_every_column_once() {
        for total in [1, 7, 21, 4096] {
            for parts in 1..=total.min(23) {
                let mut next = 0;
                for k in 0..parts {
                    let c = TablePart::columns(total, k, parts);
                    assert_eq!(c.start, next, "{total} columns in {parts} parts");
                    assert!(!c.is_empty());
                    next = c.end;
                }
                assert_eq!(next, total);
            }
        }
    }

    #[test]
    fn a_merged_table_is_the_whole_run_byte_for_byte() {
        let (atmosphere, settings) = small();
        let whole = SkylightTable::precompute(&atmosphere, &settings, &|_, _| {}).unwrap();
        // 4 parts of 21 columns: runs of 5 and 6 that split altitudes between parts.
        let parts: Vec<TablePart> = (0..4)
            .rev()
            .map(|k| {
                let part = TablePart::compute(&atmosphere, &settings, k, 4, &|_, _| {}).unwrap();
                // Through the file, as parts travel between machines.
                TablePart::from_bytes(&part.to_bytes(), "part").unwrap()
            })
            .collect();
        let merged = SkylightTable::merge(parts.clone()).unwrap();
        assert!(
            merged.to_bytes() == whole.to_bytes(),
            "the merged table differs"
        );

        let missing = SkylightTable::merge(parts[1..].to_vec())
            .unwrap_err()
            .to_string();
        assert!(missing.contains("parts 4 of 4 are missing"), "{missing}");
        let mut twice = parts.clone();
        twice.push(parts[0].clone());
        let twice = SkylightTable::merge(twice).unwrap_err().to_string();
        assert!(twice.contains("part 4 of 4 is there twice"), "{twice}");
        let other = TablePart::compute(
            &atmosphere,
            &TableSettings {
                max_altitude_m: 9_000.0,
                ..settings.clone()
            },
            0,
            4,
            &|_, _| {},
        )
        .unwrap();
        let mixed = [vec![other], parts[..3].to_vec()].concat();
        let mixed = SkylightTable::merge(mixed).unwrap_err().to_string();
        assert!(
            mixed.contains("another atmosphere or other settings"),
            "{mixed}"
        );
    }

    #[test]
    fn damaged_or_foreign_part_files_are_refused() {
        let (atmosphere, settings) = small();
        let part = TablePart::compute(&atmosphere, &settings, 20, 21, &|_, _| {}).unwrap();
        let bytes = part.to_bytes();
        let mut altered = bytes.clone();
        altered[bytes.len() / 2] ^= 1;
        let e = TablePart::from_bytes(&altered, "p")
            .unwrap_err()
            .to_string();
        assert!(e.contains("checksum"), "{e}");
        let e = TablePart::from_bytes(&bytes[..bytes.len() - 9], "p")
            .unwrap_err()
            .to_string();
        assert!(e.contains("checksum"), "{e}");
        let whole = SkylightTable::precompute(&atmosphere, &settings, &|_, _| {}).unwrap();
        let e = TablePart::from_bytes(&whole.to_bytes(), "p")
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a part"), "{e}");
        let e = TablePart::compute(&atmosphere, &settings, 21, 21, &|_, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("part 22 of 21"), "{e}");
        let e = TablePart::compute(&atmosphere, &settings, 0, 22, &|_, _| {})
            .unwrap_err()
            .to_string();
        assert!(e.contains("22 parts of a table of 21 maps"), "{e}");
    }
}
