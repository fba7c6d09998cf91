//! Gmsh meshes: a reader for MSH 4.1 (ASCII and binary) and MSH 2.2 (ASCII), and a writer of
//! MSH 4.1 ASCII.
//!
//! **Why our own reader.** The one maintained-looking crate, `mshio` (0.4.2, last release June
//! 2020), reads MSH 4.1 only, and skips `$PhysicalNames` — the names a scenario uses for the
//! boundary parts — so a reader of ours would have had to parse around it anyway; MSH 2.2 (still
//! the default of many scripts) it does not read at all. The format is small and documented, and
//! this reader is about as long as the glue around `mshio` would be, with errors that name the
//! file and the section.
//!
//! **What is read.** The mesh's dimension d is the highest dimension of its elements. Cells are
//! the elements of dimension d: 3-node triangles (type 2) in 2D, 4-node tetrahedra (type 4) in
//! 3D. Boundary parts are the **physical groups** of dimension d − 1, named by `$PhysicalNames`
//! (the tag as a decimal string when unnamed), their facets the 2-node lines (type 1) or 3-node
//! triangles (type 2) of the group's entities. A facet in several physical groups is stored
//! once per group. **Cell regions** are the physical groups of dimension d
//! ([`super::CellRegion`], named likewise): every cell of dimension d is read, in a group or
//! not, and each group keeps the list of its cells; a cell in two groups is in both lists
//! (MSH 2.2 writes such a cell once per group: the repeats, with the same nodes, are one cell).
//! Elements of dimension d − 1 in no physical group are dropped, and so are
//! nodes no element refers to (Gmsh lists geometry points, e.g. the centre of a circle arc, when
//! the whole model is saved). Second-order elements, quadrangles, hexahedra, prisms and
//! pyramids of dimension d or d − 1 are refused with what to change in Gmsh. A partitioned mesh
//! is refused. Everything is then checked by [`Mesh::new`].

use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::Path;

use super::{CellRegion, Mesh, MeshError};

/// Reads a Gmsh `.msh` file (MSH 4.1 ASCII or binary, MSH 2.2 ASCII).
pub fn read_msh(path: &Path) -> Result<Mesh, MeshError> {
    // Regular files of a size the machine can hold only (a FIFO would block forever).
    let bytes =
        crate::resources::read_input(path, crate::resources::max_data_file_bytes()).map_err(|e| MeshError::Read {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
    let raw = parse(&bytes, path)?;
    raw.into_mesh(path)
}

/// A Gmsh element type: dimension, nodes, name.
fn element_type(code: u32) -> Option<(usize, usize, &'static str)> {
    Some(match code {
        1 => (1, 2, "2-node line"),
        2 => (2, 3, "3-node triangle"),
        3 => (2, 4, "4-node quadrangle"),
        4 => (3, 4, "4-node tetrahedron"),
        5 => (3, 8, "8-node hexahedron"),
        6 => (3, 6, "6-node prism"),
        7 => (3, 5, "5-node pyramid"),
        8 => (1, 3, "3-node second-order line"),
        9 => (2, 6, "6-node second-order triangle"),
        10 => (2, 9, "9-node second-order quadrangle"),
        11 => (3, 10, "10-node second-order tetrahedron"),
        12 => (3, 27, "27-node second-order hexahedron"),
        13 => (3, 18, "18-node second-order prism"),
        14 => (3, 14, "14-node second-order pyramid"),
        15 => (0, 1, "1-node point"),
        16 => (2, 8, "8-node second-order quadrangle"),
        17 => (3, 20, "20-node second-order hexahedron"),
        18 => (3, 15, "15-node second-order prism"),
        19 => (3, 13, "13-node second-order pyramid"),
        20 => (2, 9, "9-node third-order incomplete triangle"),
        21 => (2, 10, "10-node third-order triangle"),
        22 => (2, 12, "12-node fourth-order incomplete triangle"),
        23 => (2, 15, "15-node fourth-order triangle"),
        24 => (2, 15, "15-node fifth-order incomplete triangle"),
        25 => (2, 21, "21-node fifth-order triangle"),
        26 => (1, 4, "4-node third-order line"),
        27 => (1, 5, "5-node fourth-order line"),
        28 => (1, 6, "6-node fifth-order line"),
        29 => (3, 20, "20-node third-order tetrahedron"),
        30 => (3, 35, "35-node fourth-order tetrahedron"),
        31 => (3, 56, "56-node fifth-order tetrahedron"),
        _ => return None,
    })
}

/// What to change in Gmsh for an element type this reader refuses.
fn advice(code: u32) -> &'static str {
    match element_type(code) {
        Some((_, _, name)) if name.contains("order") => "mesh with first-order elements (Mesh.ElementOrder = 1)",
        _ => "mesh with simplices only (no Recombine, no transfinite volumes with hexahedra, Mesh.SubdivisionAlgorithm = 0)",
    }
}

/// One block of elements of one type on one entity.
struct Block {
    dim: usize,
    entity: i32,
    code: u32,
    /// Node tags, `nodes` per element.
    nodes: Vec<u64>,
}

/// The file's content before it is made a mesh.
#[derive(Default)]
struct Raw {
    /// (dimension, tag) → name.
    names: HashMap<(usize, i32), String>,
    /// (dimension, entity tag) → physical tags (MSH 4.1 `$Entities`).
    entity_groups: HashMap<(usize, i32), Vec<i32>>,
    /// Node tag → coordinates.
    nodes: Vec<(u64, [f64; 3])>,
    blocks: Vec<Block>,
    /// MSH 2.2 gives the physical tag per element: (block, element) order, parallel to blocks.
    element_groups: Option<Vec<Vec<i32>>>,
}

fn parse(bytes: &[u8], path: &Path) -> Result<Raw, MeshError> {
    let mut cursor = Cursor {
        bytes,
        pos: 0,
        binary: false,
        swap: false,
        path,
        section: "MeshFormat".into(),
    };
    let first = cursor.line().map_err(|_| cursor.not_msh())?;
    if first.trim() != "$MeshFormat" {
        return Err(cursor.not_msh());
    }
    let header = cursor.line()?;
    let fields: Vec<&str> = header.split_whitespace().collect();
    let (version, file_type, data_size) = match fields.as_slice() {
        [v, t, s, ..] => (v.to_string(), *t, *s),
        _ => return Err(cursor.not_msh()),
    };
    let v4 = version.starts_with("4.1");
    if !v4 && !version.starts_with("2.2") {
        return Err(MeshError::Format {
            path: path.to_path_buf(),
            message: format!(
                "MSH version {version}: this reader reads MSH 4.1 (ASCII or binary) and 2.2 (ASCII); in Gmsh, save with -format msh41"
            ),
        });
    }
    if file_type == "1" {
        if !v4 {
            return Err(MeshError::Format {
                path: path.to_path_buf(),
                message: "binary MSH 2.2 is not read: save as MSH 4.1 (binary or ASCII) or MSH 2.2 ASCII".into(),
            });
        }
        if data_size != "8" {
            return Err(cursor.error(&format!("data size {data_size}: expected 8")));
        }
        cursor.binary = true;
        let one = cursor.bytes_n(4)?;
        cursor.swap = u32::from_le_bytes([one[0], one[1], one[2], one[3]]) != 1;
        cursor.line()?; // the rest of the line after the binary one
    }
    cursor.expect_end()?;

    let mut raw = Raw::default();
    while let Some(section) = cursor.next_section()? {
        cursor.section = section.clone();
        match section.as_str() {
            "PhysicalNames" => parse_names(&mut cursor, &mut raw)?,
            "Entities" if v4 => parse_entities(&mut cursor, &mut raw)?,
            "Nodes" if v4 => parse_nodes4(&mut cursor, &mut raw)?,
            "Elements" if v4 => parse_elements4(&mut cursor, &mut raw)?,
            "Nodes" => parse_nodes2(&mut cursor, &mut raw)?,
            "Elements" => parse_elements2(&mut cursor, &mut raw)?,
            "PartitionedEntities" => {
                return Err(MeshError::Format {
                    path: path.to_path_buf(),
                    message: "a partitioned mesh: save it unpartitioned (Mesh.PartitionSplitMeshFiles = 0, no -part)"
                        .into(),
                })
            }
            _ => {
                cursor.skip_section()?;
                continue;
            }
        }
        cursor.expect_end()?;
    }
    if raw.nodes.is_empty() || raw.blocks.is_empty() {
        return Err(MeshError::Format {
            path: path.to_path_buf(),
            message: "no $Nodes or no $Elements section".into(),
        });
    }
    Ok(raw)
}

fn parse_names(c: &mut Cursor, raw: &mut Raw) -> Result<(), MeshError> {
    // Always ASCII, also in binary files.
    let binary = std::mem::replace(&mut c.binary, false);
    let n = c.count(6, 6, "physical names")?;
    c.line()?; // the end of the count's line
    for _ in 0..n {
        let line = c.line()?;
        let mut parts = line.trim().splitn(3, char::is_whitespace);
        let (Some(dim), Some(tag), Some(name)) = (parts.next(), parts.next(), parts.next()) else {
            return Err(c.error(&format!("expected `dimension tag \"name\"`, found `{line}`")));
        };
        let dim: usize = dim
            .parse()
            .map_err(|_| c.error(&format!("bad dimension in `{line}`")))?;
        let tag: i32 = tag.parse().map_err(|_| c.error(&format!("bad tag in `{line}`")))?;
        raw.names.insert((dim, tag), name.trim().trim_matches('"').to_string());
    }
    c.binary = binary;
    Ok(())
}

fn parse_entities(c: &mut Cursor, raw: &mut Raw) -> Result<(), MeshError> {
    let counts = [c.size()?, c.size()?, c.size()?, c.size()?];
    for (dim, &count) in counts.iter().enumerate() {
        for _ in 0..count {
            let tag = c.int()?;
            let coordinates = if dim == 0 { 3 } else { 6 };
            for _ in 0..coordinates {
                c.float()?;
            }
            let n_groups = c.size()?;
            let groups = (0..n_groups).map(|_| c.int()).collect::<Result<Vec<i32>, _>>()?;
            if dim > 0 {
                let n_bounding = c.size()?;
                for _ in 0..n_bounding {
                    c.int()?;
                }
            }
            raw.entity_groups.insert((dim, tag), groups);
        }
    }
    Ok(())
}

fn parse_nodes4(c: &mut Cursor, raw: &mut Raw) -> Result<(), MeshError> {
    // A node takes at least its tag and three coordinates: 8 bytes in ASCII, 32 in binary.
    let (n_blocks, n_nodes) = (c.count(8, 20, "node blocks")?, c.count(8, 32, "nodes")?);
    c.size_u64()?; // the smallest and largest tags: any values (sparse or offset tags)
    c.size_u64()?;
    raw.nodes.reserve(n_nodes);
    for _ in 0..n_blocks {
        let (dim, _entity, parametric) = (c.int()?, c.int()?, c.int()?);
        let n = c.count(8, 32, "nodes in a block")?;
        let tags = (0..n).map(|_| c.size_u64()).collect::<Result<Vec<u64>, _>>()?;
        let extra = if parametric != 0 { dim.clamp(0, 3) as usize } else { 0 };
        for tag in tags {
            let x = [c.float()?, c.float()?, c.float()?];
            for _ in 0..extra {
                c.float()?;
            }
            raw.nodes.push((tag, x));
        }
    }
    Ok(())
}

fn parse_elements4(c: &mut Cursor, raw: &mut Raw) -> Result<(), MeshError> {
    let n_blocks = c.count(8, 20, "element blocks")?;
    c.size_u64()?; // the number of elements, the smallest and the largest tag: not needed
    c.size_u64()?;
    c.size_u64()?;
    for _ in 0..n_blocks {
        let (dim, entity, code) = (c.int()?, c.int()?, c.int()?);
        let code = code as u32;
        let Some((_, per, _)) = element_type(code) else {
            return Err(c.error(&format!("unknown element type {code}")));
        };
        // An element takes at least its tag and `per` node tags: 2 bytes each in ASCII, 8 in
        // binary; the reservation below is then at most 4× the rest of the file.
        let per64 = per as u64;
        let n = c.count(2 * (1 + per64), 8 * (1 + per64), "elements in a block")?;
        let mut nodes = Vec::with_capacity(n * per);
        for _ in 0..n {
            c.size_u64()?; // element tag
            for _ in 0..per {
                nodes.push(c.size_u64()?);
            }
        }
        raw.blocks.push(Block {
            dim: dim.clamp(0, 3) as usize,
            entity,
            code,
            nodes,
        });
    }
    Ok(())
}

fn parse_nodes2(c: &mut Cursor, raw: &mut Raw) -> Result<(), MeshError> {
    let n = c.count(8, 8, "nodes")?;
    raw.nodes.reserve(n);
    for _ in 0..n {
        let tag = c.size_u64()?;
        raw.nodes.push((tag, [c.float()?, c.float()?, c.float()?]));
    }
    Ok(())
}

fn parse_elements2(c: &mut Cursor, raw: &mut Raw) -> Result<(), MeshError> {
    // An element takes at least its tag, type, number of tags and two nodes: 10 bytes.
    let n = c.count(10, 10, "elements")?;
    let mut groups: Vec<Vec<i32>> = Vec::new();
    for _ in 0..n {
        c.size_u64()?; // element tag
        let code = c.int()? as u32;
        let n_tags = c.size()?;
        let tags = (0..n_tags).map(|_| c.int()).collect::<Result<Vec<i32>, _>>()?;
        let Some((dim, per, _)) = element_type(code) else {
            return Err(c.error(&format!("unknown element type {code}")));
        };
        let nodes = (0..per).map(|_| c.size_u64()).collect::<Result<Vec<u64>, _>>()?;
        // One block per element keeps the 2.2 and 4.1 paths alike; the physical tag is the first.
        raw.blocks.push(Block {
            dim,
            entity: tags.get(1).copied().unwrap_or(0),
            code,
            nodes,
        });
        groups.push(tags.first().copied().filter(|&g| g != 0).into_iter().collect());
    }
    raw.element_groups = Some(groups);
    Ok(())
}

impl Raw {
    fn into_mesh(self, path: &Path) -> Result<Mesh, MeshError> {
        let dim = self.blocks.iter().map(|b| b.dim).max().unwrap_or(0);
        if dim < 2 {
            return Err(MeshError::Format {
                path: path.to_path_buf(),
                message: format!("the highest element dimension is {dim}: expected a 2D or 3D mesh"),
            });
        }
        let (cell_code, facet_code) = if dim == 2 { (2, 1) } else { (4, 2) };
        if let Some(b) = self
            .blocks
            .iter()
            .find(|b| (b.dim == dim && b.code != cell_code) || (b.dim + 1 == dim && b.code != facet_code))
        {
            return Err(MeshError::UnsupportedElement {
                path: path.to_path_buf(),
                code: b.code,
                name: element_type(b.code).map_or("unknown", |t| t.2).to_string(),
                dim,
                advice: advice(b.code).to_string(),
            });
        }
        let (used, coords) = self.node_indices(path)?;
        let index = |tag: &u64| -> Result<usize, MeshError> {
            used.get(tag).copied().flatten().ok_or_else(|| MeshError::Format {
                path: path.to_path_buf(),
                message: format!("an element refers to node {tag}, which $Nodes does not list"),
            })
        };
        let mut cells = Vec::new();
        // Physical group tag → its facets' nodes (dimension d − 1), its cells (dimension d).
        let mut parts: BTreeMap<i32, Vec<usize>> = BTreeMap::new();
        let mut groups_of_cells: BTreeMap<i32, Vec<u32>> = BTreeMap::new();
        // MSH 2.2 lists a cell once per physical group it is in: the repeats are one cell.
        let mut listed: HashMap<[u64; 4], u32> = HashMap::new();
        for (i, b) in self.blocks.iter().enumerate() {
            let groups: &[i32] = match &self.element_groups {
                Some(per_element) => &per_element[i],
                None => self.entity_groups.get(&(b.dim, b.entity)).map_or(&[], Vec::as_slice),
            };
            if b.dim == dim {
                for element in b.nodes.chunks_exact(dim + 1) {
                    let mut key = [0; 4];
                    key[..=dim].copy_from_slice(element);
                    key.sort_unstable();
                    let fresh = (cells.len() / (dim + 1)) as u32;
                    let cell = match self.element_groups {
                        Some(_) => *listed.entry(key).or_insert(fresh),
                        None => fresh,
                    };
                    if cell == fresh {
                        for tag in element {
                            cells.push(index(tag)?);
                        }
                    }
                    for &group in groups {
                        groups_of_cells.entry(group).or_default().push(cell);
                    }
                }
            } else if b.dim + 1 == dim {
                for &group in groups {
                    let facets = parts.entry(group).or_default();
                    for tag in &b.nodes {
                        facets.push(index(tag)?);
                    }
                }
            }
        }
        let name = |dim: usize, group: i32| {
            self.names
                .get(&(dim, group))
                .cloned()
                .unwrap_or_else(|| group.to_string())
        };
        let mut facets = Vec::new();
        let mut facet_parts = Vec::new();
        let mut part_names = Vec::new();
        for (k, (group, nodes)) in parts.into_iter().enumerate() {
            facet_parts.extend(std::iter::repeat_n(k, nodes.len() / dim));
            facets.extend(nodes);
            part_names.push(name(dim - 1, group));
        }
        let regions = (groups_of_cells.into_iter())
            .map(|(group, cells)| CellRegion {
                name: name(dim, group),
                cells,
            })
            .collect();
        Mesh::new(dim, coords, cells, facets, facet_parts, part_names)
            .and_then(|mesh| mesh.with_regions(regions))
            .map_err(|e| e.in_file(path))
    }

    /// Node tags → compact indices, in order of the file, keeping the nodes some element uses;
    /// and their coordinates. A node defined twice is an error.
    #[allow(clippy::type_complexity)]
    fn node_indices(&self, path: &Path) -> Result<(HashMap<u64, Option<usize>>, Vec<[f64; 3]>), MeshError> {
        // A node defined twice would be moved silently by its later definition.
        let mut defined = std::collections::HashSet::with_capacity(self.nodes.len());
        if let Some((tag, _)) = self.nodes.iter().find(|(tag, _)| !defined.insert(*tag)) {
            return Err(MeshError::Format {
                path: path.to_path_buf(),
                message: format!("node {tag} is defined twice in $Nodes (each node tag once)"),
            });
        }
        let mut used: HashMap<u64, Option<usize>> = HashMap::new();
        for b in &self.blocks {
            for &tag in &b.nodes {
                used.insert(tag, None);
            }
        }
        let mut coords = Vec::with_capacity(used.len());
        for (tag, x) in &self.nodes {
            if let Some(index @ None) = used.get_mut(tag) {
                *index = Some(coords.len());
                coords.push(*x);
            }
        }
        Ok((used, coords))
    }
}

/// A position in the file's bytes, reading ASCII tokens or binary values.
struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    binary: bool,
    /// Binary data written big-endian.
    swap: bool,
    path: &'a Path,
    section: String,
}

impl Cursor<'_> {
    fn error(&self, message: &str) -> MeshError {
        MeshError::Section {
            path: self.path.to_path_buf(),
            section: self.section.clone(),
            message: message.to_string(),
        }
    }

    fn not_msh(&self) -> MeshError {
        MeshError::Format {
            path: self.path.to_path_buf(),
            message: "not a Gmsh mesh file (it does not start with $MeshFormat)".into(),
        }
    }

    fn truncated(&self) -> MeshError {
        self.error("the file ends inside the section (truncated)")
    }

    fn line(&mut self) -> Result<String, MeshError> {
        if self.pos >= self.bytes.len() {
            return Err(self.truncated());
        }
        let rest = &self.bytes[self.pos..];
        let end = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        self.pos += (end + 1).min(rest.len());
        Ok(String::from_utf8_lossy(&rest[..end]).trim_end_matches('\r').to_string())
    }

    fn token(&mut self) -> Result<&str, MeshError> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        let start = self.pos;
        while self.pos < self.bytes.len() && !self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if start == self.pos {
            return Err(self.truncated());
        }
        std::str::from_utf8(&self.bytes[start..self.pos]).map_err(|_| self.error("a token that is not text"))
    }

    fn parse_token<T: std::str::FromStr>(&mut self, what: &str) -> Result<T, MeshError> {
        let token = self.token()?.to_string();
        if token.starts_with('$') {
            return Err(self.error(&format!("ends early: found {token} where {what} was expected")));
        }
        token
            .parse()
            .map_err(|_| self.error(&format!("`{token}` is not {what}")))
    }

    fn bytes_n(&mut self, n: usize) -> Result<&[u8], MeshError> {
        if self.pos + n > self.bytes.len() {
            return Err(self.truncated());
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    fn array<const N: usize>(&mut self) -> Result<[u8; N], MeshError> {
        let swap = self.swap;
        let mut a: [u8; N] = self.bytes_n(N)?.try_into().expect("N bytes");
        if swap {
            a.reverse();
        }
        Ok(a)
    }

    /// A C `int`.
    fn int(&mut self) -> Result<i32, MeshError> {
        if self.binary {
            Ok(i32::from_le_bytes(self.array::<4>()?))
        } else {
            self.parse_token("an integer")
        }
    }

    /// A `size_t` (counts and tags).
    fn size_u64(&mut self) -> Result<u64, MeshError> {
        if self.binary {
            Ok(u64::from_le_bytes(self.array::<8>()?))
        } else {
            self.parse_token("a non-negative integer")
        }
    }

    /// A small count (of entities, groups, tags), bounded by what the rest of the file holds.
    fn size(&mut self) -> Result<usize, MeshError> {
        self.count(2, 4, "items")
    }

    /// A count of `what`, each taking at least `ascii` bytes in an ASCII file (`binary` in a
    /// binary one), refused when the rest of the file cannot hold that many: whatever is
    /// reserved from a count is then a few times the file's size at most, never what a
    /// damaged or hostile count asks for.
    fn count(&mut self, ascii: u64, binary: u64, what: &str) -> Result<usize, MeshError> {
        let n = self.size_u64()?;
        let need = n.saturating_mul(if self.binary { binary } else { ascii });
        let rest = (self.bytes.len() - self.pos) as u64;
        if need > rest {
            return Err(self.error(&format!(
                "{n} {what} need at least {need} bytes, but {rest} remain in the file (a wrong count, or a truncated file)"
            )));
        }
        Ok(n as usize)
    }

    fn float(&mut self) -> Result<f64, MeshError> {
        if self.binary {
            Ok(f64::from_le_bytes(self.array::<8>()?))
        } else {
            self.parse_token("a number")
        }
    }

    /// The next `$Section` header, skipping blank space; `None` at the end of the file.
    fn next_section(&mut self) -> Result<Option<String>, MeshError> {
        while self.pos < self.bytes.len() && self.bytes[self.pos].is_ascii_whitespace() {
            self.pos += 1;
        }
        if self.pos >= self.bytes.len() {
            return Ok(None);
        }
        let line = self.line()?;
        match line.trim().strip_prefix('$') {
            Some(name) => Ok(Some(name.to_string())),
            None => Err(self.error(&format!("expected a $Section after it, found `{line}`"))),
        }
    }

    /// Checks that `$End<section>` follows.
    fn expect_end(&mut self) -> Result<(), MeshError> {
        let binary = std::mem::replace(&mut self.binary, false);
        let token = self.token().map(str::to_string);
        self.binary = binary;
        let expected = format!("$End{}", self.section);
        match token {
            Ok(t) if t == expected => {
                // The rest of the line, if the file goes on (its final newline may be missing).
                if self.pos < self.bytes.len() {
                    self.line()?;
                }
                Ok(())
            }
            Ok(t) => Err(self.error(&format!(
                "found `{t}` where {expected} was expected (a count does not match)"
            ))),
            Err(_) => Err(self.truncated()),
        }
    }

    /// Skips a section this reader does not use.
    fn skip_section(&mut self) -> Result<(), MeshError> {
        let end = format!("\n$End{}", self.section);
        let rest = &self.bytes[self.pos.saturating_sub(1)..];
        let at = rest
            .windows(end.len())
            .position(|w| w == end.as_bytes())
            .ok_or_else(|| self.truncated())?;
        self.pos = self.pos.saturating_sub(1) + at + 1;
        if self.pos < self.bytes.len() {
            self.line()?;
        }
        Ok(())
    }
}

/// The mesh as MSH 4.1 ASCII: one entity per boundary part with a physical group of that name
/// (tags 1, 2, …); the cells on one entity per set of cell regions they are in, each region a
/// physical group of dimension d (tags after the parts'), and the cells in no region (entity 1)
/// in a physical group `domain` (the last tag): every element has a physical group, as meshio
/// and other readers expect (a mesh without regions gives the text of before regions existed).
/// Node tags are the indices + 1. Reading the text back with [`read_msh`] gives the same mesh,
/// regions included, plus a region `domain` of the cells that were in none (a mesh with regions
/// comes back with its cells grouped by the regions they are in, in their order within each
/// group).
pub fn msh_text(mesh: &Mesh) -> String {
    let d = mesh.dim;
    let n_parts = mesh.part_names.len();
    // The cells of each set of regions, the set of no region first.
    let mut in_regions: Vec<Vec<usize>> = vec![Vec::new(); mesh.n_cells()];
    for (r, region) in mesh.regions.iter().enumerate() {
        for &e in &region.cells {
            in_regions[e as usize].push(n_parts + 1 + r);
        }
    }
    let domain = n_parts + 1 + mesh.regions.len();
    let mut entities: BTreeMap<Vec<usize>, Vec<usize>> = BTreeMap::new();
    for (e, groups) in in_regions.into_iter().enumerate() {
        entities.entry(groups).or_default().push(e);
    }
    let has_domain = entities.contains_key(&Vec::new());
    let mut s = String::new();
    let _ = writeln!(s, "$MeshFormat\n4.1 0 8\n$EndMeshFormat");
    let n_physical = n_parts + mesh.regions.len() + usize::from(has_domain);
    let _ = writeln!(s, "$PhysicalNames\n{n_physical}");
    for (k, name) in mesh.part_names.iter().enumerate() {
        let _ = writeln!(s, "{} {} \"{name}\"", d - 1, k + 1);
    }
    for (r, region) in mesh.regions.iter().enumerate() {
        let _ = writeln!(s, "{d} {} \"{}\"", n_parts + 1 + r, region.name);
    }
    if has_domain {
        let _ = writeln!(s, "{d} {domain} \"domain\"");
    }
    let _ = writeln!(s, "$EndPhysicalNames");
    // Entities: no points; the parts' entities of dimension d − 1 and the cells' of dimension d.
    // The bounding boxes are not used by readers of meshes; zeros keep the text short.
    let mut counts = [0usize; 4];
    counts[d - 1] = n_parts;
    counts[d] = entities.len();
    let _ = writeln!(s, "$Entities\n{} {} {} {}", counts[0], counts[1], counts[2], counts[3]);
    for k in 0..n_parts {
        let _ = writeln!(s, "{} 0 0 0 0 0 0 1 {} 0", k + 1, k + 1);
    }
    for (k, groups) in entities.keys().enumerate() {
        let groups = if groups.is_empty() {
            vec![domain]
        } else {
            groups.clone()
        };
        let tags: String = groups.iter().map(|g| format!(" {g}")).collect();
        let _ = writeln!(s, "{} 0 0 0 0 0 0 {}{tags} 0", k + 1, groups.len());
    }
    let _ = writeln!(s, "$EndEntities");
    let n = mesh.n_nodes();
    let _ = writeln!(s, "$Nodes\n1 {n} 1 {n}\n{d} 1 0 {n}");
    for p in 1..=n {
        let _ = writeln!(s, "{p}");
    }
    for x in &mesh.coords {
        let _ = writeln!(s, "{:?} {:?} {:?}", x[0], x[1], x[2]);
    }
    let _ = writeln!(s, "$EndNodes");
    let n_elements = mesh.n_cells() + mesh.n_facets();
    let _ = writeln!(s, "$Elements\n{} {n_elements} 1 {n_elements}", n_parts + entities.len());
    let mut tag = 0;
    let (cell_code, facet_code) = if d == 2 { (2, 1) } else { (4, 2) };
    let mut write_elements = |s: &mut String, header: String, elements: &mut dyn Iterator<Item = &[usize]>| {
        let _ = writeln!(s, "{header}");
        for nodes in elements {
            tag += 1;
            let nodes: Vec<String> = nodes.iter().map(|p| (p + 1).to_string()).collect();
            let _ = writeln!(s, "{tag} {}", nodes.join(" "));
        }
    };
    for k in 0..n_parts {
        let facets: Vec<usize> = (0..mesh.n_facets()).filter(|&f| mesh.facet_parts[f] == k).collect();
        let header = format!("{} {} {facet_code} {}", d - 1, k + 1, facets.len());
        write_elements(&mut s, header, &mut facets.iter().map(|&f| mesh.facet(f)));
    }
    for (k, cells) in entities.values().enumerate() {
        let header = format!("{d} {} {cell_code} {}", k + 1, cells.len());
        write_elements(&mut s, header, &mut cells.iter().map(|&e| mesh.cell(e)));
    }
    let _ = writeln!(s, "$EndElements");
    s
}
