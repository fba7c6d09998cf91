//! Reading a scenario: the text of a file (or none), laid over the built-in default key by key,
//! then the `--set key=value` overrides; unknown and removed keys are refused by name, and a
//! deserialization error is turned into one that names the dotted key.

use std::path::Path;
use std::sync::Arc;

use toml::{Table, Value};

use super::schema::LoadedMesh;
use super::validate::invalid;
use super::{FrictionSpec, Scenario};
use crate::error::Error;
use crate::mesh::{self, Mesh};

/// The default scenario (the paper's example), with comments.
pub const DEFAULT_TOML: &str = include_str!("../../scenarios/paper.toml");

/// The largest scenario file read (1 MiB).
pub const MAX_SCENARIO_BYTES: u64 = 1 << 20;

impl Default for Scenario {
    fn default() -> Self {
        Scenario::load(None, &[]).expect("the built-in scenario is valid")
    }
}

impl Scenario {
    /// Loads a scenario: the built-in default, overlaid by the file's text (if any), overlaid by
    /// `key.path=value` overrides; then validated. A relative `mesh.file` is taken relative to
    /// the current directory.
    pub fn load(file_text: Option<&str>, overrides: &[String]) -> Result<Self, Error> {
        Self::load_in(file_text, overrides, None, None)
    }

    /// [`Scenario::load`] on a mesh given in memory (built by a program, e.g. from arrays): the
    /// mesh replaces the structured generator as a `mesh.file` does — the default's geometry,
    /// cell counts and tractions (on the rectangle's parts) go — and the boundary parts named in
    /// the text and overrides are checked against the mesh's. The text may hold no `geometry`
    /// and no `mesh` keys. The mesh is not part of [`Scenario::to_toml`]: load that text again
    /// with the same mesh.
    ///
    /// ```
    /// use thermocontact::{mesh, Scenario};
    /// let m = mesh::rectangle(40.0, 10.0, 8, 2); // parts left, right, bottom, top
    /// let s = Scenario::load_with_mesh(None, &["time.steps=4".into()], m).unwrap();
    /// assert_eq!((s.dim(), s.structured(), s.time.steps), (2, None, 4));
    /// ```
    pub fn load_with_mesh(
        file_text: Option<&str>,
        overrides: &[String],
        mesh: impl Into<Arc<Mesh>>,
    ) -> Result<Self, Error> {
        Self::load_in(file_text, overrides, None, Some(mesh.into()))
    }

    /// [`Scenario::load`] from a file: a relative `mesh.file` in it is taken relative to the
    /// file's folder.
    pub fn load_file(path: &Path, overrides: &[String]) -> Result<Self, Error> {
        // A scenario is a page of settings; data arrays belong in mesh files. Parsing holds
        // ~60× the text in memory, so a huge file is refused before it is read.
        let bytes = crate::resources::read_input(path, MAX_SCENARIO_BYTES).map_err(|source| Error::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let text = String::from_utf8(bytes).map_err(|_| {
            Error::Scenario(format!(
                "{} is not UTF-8 text (a scenario is a TOML file)",
                path.display()
            ))
        })?;
        Self::load_in(Some(&text), overrides, path.parent(), None).map_err(|e| match e {
            // A syntax error is about the file: name it (keys and values name themselves).
            Error::Scenario(message) if message.starts_with(NOT_TOML) => {
                Error::Scenario(format!("{}: {message}", path.display()))
            }
            e => e,
        })
    }

    fn load_in(
        file_text: Option<&str>,
        overrides: &[String],
        folder: Option<&Path>,
        given: Option<Arc<Mesh>>,
    ) -> Result<Self, Error> {
        let mut table: Table = DEFAULT_TOML.parse().expect("built-in scenario parses");
        if given.is_some() {
            drop_generator(&mut table);
        }
        if let Some(text) = file_text {
            let mut user: Table = text
                .parse()
                .map_err(|e: toml::de::Error| Error::Scenario(format!("{NOT_TOML}: {e}")))?;
            resolve_mesh_file(&mut user, folder);
            if given.is_some() {
                refuse_mesh_keys(&user)?;
            }
            overlay(&mut table, user, "")?;
        }
        // All overrides form one table laid over at once, so that `friction.law=tresca` and
        // `friction.bound=100` together switch the law (one at a time, the second would meet
        // the first's table, which the switch has emptied).
        // Two overrides of one key: the later wins, with a warning (a command line edited by
        // appending is common); one that sets a key inside another's value, or a value over
        // another's keys, is refused naming both (the first would vanish without a word).
        let mut assigned = Table::new();
        let mut earlier: Vec<(&str, Table)> = Vec::new();
        let mut repeated = Vec::new();
        for assignment in overrides {
            let parsed = parse_override(assignment)?;
            for (before, table) in &earlier {
                match overlap(table, &parsed, "") {
                    Some(Overlap::Same(key)) => repeated.push(format!(
                        "--set {key} is given twice ({before:?}, then {assignment:?}): the later one is used"
                    )),
                    Some(Overlap::Nested(key)) => {
                        return Err(Error::InvalidValue {
                            key: key.clone(),
                            value: format!("--set {before:?} and --set {assignment:?}"),
                            expected: format!(
                                "one of them: the second replaces the first's `{key}` (pass the whole table in one --set, or only the keys inside it)"
                            ),
                        })
                    }
                    None => {}
                }
            }
            merge(&mut assigned, parsed.clone());
            earlier.push((assignment.as_str(), parsed));
        }
        if given.is_some() {
            refuse_mesh_keys(&assigned)?;
        }
        overlay(&mut table, assigned, "")?;
        let text = toml::to_string(&table).map_err(|e| Error::Scenario(e.to_string()))?;
        let mut scenario: Scenario = toml::from_str(&text).map_err(|e| describe(&e, &text))?;
        scenario.rename_deprecated();
        scenario.warnings.extend(repeated);
        if let Some(mesh) = given {
            scenario.loaded = LoadedMesh(Some(mesh));
        }
        if let Some(from) = &mut scenario.initial.from {
            *from = std::path::absolute(&*from).unwrap_or_else(|_| from.clone());
        }
        if let Some(file) = &mut scenario.mesh.file {
            *file = std::path::absolute(&*file).unwrap_or_else(|_| file.clone());
            let mesh = mesh::read_msh(file).map_err(Error::Mesh)?;
            scenario.loaded = LoadedMesh(Some(Arc::new(mesh)));
        }
        scenario.warn_merged_regions();
        scenario.validate()?;
        Ok(scenario)
    }

    /// A mesh with several cell regions and no `[[regions]]`: every cell takes `[material]`,
    /// which may not be what the regions were drawn for (a warning, once).
    fn warn_merged_regions(&mut self) {
        let Some(mesh) = &self.loaded.0 else { return };
        if mesh.regions.len() > 1 && self.regions.is_empty() {
            self.warnings.push(format!(
                "the mesh has {} cell regions {:?} and no [[regions]] is given: every cell takes [material] \
                 (give a region its own material with a [[regions]] table, part = \"…\")",
                mesh.regions.len(),
                mesh.region_names()
            ));
        }
    }

    /// Renames `law = "slip-weakening"` (the former name of the paper's velocity-weakening law)
    /// and records a warning.
    fn rename_deprecated(&mut self) {
        for law in self.friction.laws_mut() {
            if let FrictionSpec::SlipWeakening {
                part,
                bound,
                normal,
                a,
                b,
                alpha,
            } = law
            {
                *law = FrictionSpec::VelocityWeakening {
                    part: part.take(),
                    bound: bound.clone(),
                    normal: *normal,
                    a: *a,
                    b: *b,
                    alpha: *alpha,
                };
                self.warnings.push(
                    "friction.law = \"slip-weakening\" is deprecated: the paper's law weakens with slip rate, so it is \
                     named \"velocity-weakening\" (slip weakening means weakening with slip distance: \
                     \"slip-distance-weakening\")"
                        .to_string(),
                );
            }
        }
    }

    /// The scenario as TOML (what a run saves beside its results).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).expect("a scenario serializes")
    }
}

/// Paths in a scenario file (`mesh.file`, `initial.from`) are relative to its folder.
fn resolve_mesh_file(user: &mut Table, folder: Option<&Path>) {
    let Some(folder) = folder else {
        return;
    };
    // A friction table's `file` (one table or one per contact part).
    let absolute = |file: &mut String| {
        if Path::new(file.as_str()).is_relative() {
            *file = folder.join(&*file).to_string_lossy().into_owned();
        }
    };
    match user.get_mut("friction") {
        Some(Value::Table(t)) => {
            if let Some(Value::String(file)) = t.get_mut("file") {
                absolute(file);
            }
        }
        Some(Value::Array(laws)) => {
            for law in laws {
                if let Some(Value::String(file)) = law.as_table_mut().and_then(|t| t.get_mut("file")) {
                    absolute(file);
                }
            }
        }
        _ => {}
    }
    for (table, key) in [("mesh", "file"), ("initial", "from")] {
        if let Some(Value::Table(t)) = user.get_mut(table) {
            if let Some(Value::String(file)) = t.get_mut(key) {
                if Path::new(file.as_str()).is_relative() {
                    *file = folder.join(file.as_str()).to_string_lossy().into_owned();
                }
            }
        }
    }
}

/// The error for `key` (at `path`), unknown to the table `base`: every key the table may hold
/// (its own and the optional ones under the same prefix), and the nearest by spelling.
fn unknown_key(base: &Table, key: &str, path: String) -> Error {
    let prefix = path.strip_suffix(key).unwrap_or("");
    let mut known: Vec<&str> = base.keys().map(String::as_str).collect();
    known.extend(
        OPTIONAL_KEYS
            .iter()
            .filter_map(|k| k.strip_prefix(prefix))
            .filter(|k| !k.contains('.')),
    );
    known.sort_unstable();
    known.dedup();
    let mut expected = known.iter().map(|k| format!("`{k}`")).collect::<Vec<_>>().join(", ");
    let nearest = known
        .iter()
        .map(|k| (edit_distance(k, key), *k))
        .min()
        .filter(|&(d, k)| d <= 2.max(k.len() / 3));
    if let Some((_, k)) = nearest {
        expected += &format!("; did you mean `{prefix}{k}`?");
    }
    Error::UnknownKey { key: path, expected }
}

/// Levenshtein distance (keys are short).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut diagonal = row[0];
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let next = (row[j + 1] + 1).min(row[j] + 1).min(diagonal + usize::from(ca != *cb));
            diagonal = row[j + 1];
            row[j + 1] = next;
        }
    }
    row[b.len()]
}

/// Turns a deserialization error into one that names the dotted key it failed at, found from
/// the error's span in the (re-serialized) scenario text.
fn describe(e: &toml::de::Error, text: &str) -> Error {
    let message = e.message().trim().to_string();
    let Some(span) = e.span() else {
        return Error::Scenario(message);
    };
    let before = &text[..span.start.min(text.len())];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line_end = text[line_start..].find('\n').map_or(text.len(), |i| line_start + i);
    let line = &text[line_start..line_end];
    let header = |l: &str| {
        l.trim()
            .strip_prefix('[')
            .map(|t| t.trim_matches(|c| c == '[' || c == ']').to_string())
    };
    if let Some(table) = header(line) {
        // An unknown `law` (serde names the tag after the message: "… in `law`").
        if let Some((variant, expected)) = unknown_variant(&message) {
            // "[[friction]] number 2: unknown variant …" keeps its entry.
            let entry = message
                .split_once("unknown variant")
                .map_or("", |(p, _)| p.trim_end_matches([' ', ':']));
            let within = if entry.is_empty() {
                String::new()
            } else {
                format!(" ({entry})")
            };
            return Error::InvalidValue {
                key: format!("{table}.law"),
                value: format!("\"{variant}\"{within}"),
                expected: format!("one of {expected}"),
            };
        }
        // The error is about the table as a whole (a key it lacks or must not have).
        if let Some(field) = missing_field(&message) {
            return Error::MissingKey {
                key: format!("{table}.{field}"),
            };
        }
        return Error::Scenario(format!("in `{table}`: {message}"));
    }
    let table = before[..line_start].lines().rev().find_map(header);
    let Some((key, value)) = line.split_once('=') else {
        return Error::Scenario(message);
    };
    let key = match table {
        Some(t) => format!("{t}.{}", key.trim()),
        None => key.trim().to_string(),
    };
    Error::InvalidValue {
        key,
        value: value.trim().to_string(),
        expected: plain(&message),
    }
}

/// The field of serde's "missing field `bound`".
fn missing_field(message: &str) -> Option<&str> {
    message.strip_prefix("missing field `")?.strip_suffix('`')
}

/// The variant and the list of serde's "unknown variant `tabel`, expected one of `a`, `b`".
fn unknown_variant(message: &str) -> Option<(&str, &str)> {
    let rest = message.split_once("unknown variant `")?.1;
    let (variant, rest) = rest.split_once('`')?;
    let expected = rest.split_once("expected one of ")?.1.lines().next()?;
    Some((variant, expected.trim()))
}

/// serde's "invalid value: integer `-1`, expected usize" as what a user should write.
fn plain(message: &str) -> String {
    if let Some((_, expected)) = unknown_variant(message) {
        return format!("one of {expected}");
    }
    match message.rsplit_once(", expected ") {
        Some((_, "usize" | "u64" | "u32")) => "a non-negative integer".into(),
        Some((_, "a string")) => "a string".into(),
        Some((_, "a boolean")) => "true or false".into(),
        Some((_, expected)) if message.starts_with("invalid ") => expected.to_string(),
        _ => message.to_string(),
    }
}

/// The start of the message for a scenario text that is not TOML.
const NOT_TOML: &str = "the file is not valid TOML";

/// Keys a scenario may hold that the default (a 2D scenario) does not: they are taken as given
/// and checked when the scenario is read.
const OPTIONAL_KEYS: &[&str] = &[
    "mesh.nz",
    "mesh.file",
    "boundary.symmetry",
    "loads.pressure",
    "initial.from",
    "friction.part",
    "friction.normal",
    "friction.bound",
    "foundation",
    "frictional_heating.value",
    "frictional_heating.friction_power",
    "thermal",
    "regions",
];

/// Data keys: a number, an array, a `{ constant, rate }` table or expression strings may replace
/// any of these forms ([`DatumSpec`] checks the new value).
const DATUM_KEYS: &[&str] = &[
    "friction.bound",
    "loads.body_force",
    "loads.heat_source",
    "initial.displacement",
    "initial.velocity",
    "initial.temperature",
];

/// Keys that existed once, with what replaced them.
const REMOVED_KEYS: &[(&str, &str)] = &[(
    "boundary.contact_normal",
    "each contact node's outward normal now comes from the mesh; remove the key",
)];

/// Lays `user` over `base`, key by key. A key unknown to the base is an error naming its path. A
/// table whose `law` changes is replaced whole, since its keys depend on the law; a `mesh.file`
/// replaces the structured generator (the base's geometry and cell counts go).
fn overlay(base: &mut Table, user: Table, prefix: &str) -> Result<(), Error> {
    if prefix.is_empty() {
        take_mesh_file(base, &user)?;
    }
    for (key, value) in user {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        if let Some((_, instead)) = REMOVED_KEYS.iter().find(|(removed, _)| *removed == path) {
            return Err(Error::RemovedKey {
                key: path,
                instead: instead.to_string(),
            });
        }
        if prefix == "mesh" && base.contains_key("file") && ["nx", "ny", "nz"].contains(&key.as_str()) {
            return Err(invalid(
                &path,
                &value.to_string(),
                "no cell counts beside mesh.file (they belong to the structured generator)",
            ));
        }
        if prefix.is_empty() && key == "geometry" && !base.contains_key("geometry") {
            return Err(invalid(
                "geometry",
                &value.to_string(),
                "no geometry beside mesh.file (the mesh file gives the geometry)",
            ));
        }
        if path == "regions" {
            let checked = regions(base, value)?;
            base.insert(key, checked);
            continue;
        }
        if !base.contains_key(&key) && OPTIONAL_KEYS.contains(&path.as_str()) {
            base.insert(key, value);
            continue;
        }
        let Some(slot) = base.get_mut(&key) else {
            return Err(unknown_key(base, &key, path));
        };
        if DATUM_KEYS.contains(&path.as_str()) {
            *slot = value;
            continue;
        }
        // One law per contact part ([[friction]]) replaces the single table, and back.
        if path == "friction" && (slot.is_array() || value.is_array()) {
            *slot = value;
            continue;
        }
        match (slot, value) {
            (Value::Table(b), Value::Table(u)) => {
                let tag = ["law"].into_iter().find(|t| b.contains_key(*t));
                let replaced = tag.is_some_and(|t| u.get(t).is_some_and(|v| Some(v) != b.get(t)));
                if replaced {
                    *b = u;
                } else {
                    overlay(b, u, &path)?;
                }
            }
            (slot, value) => {
                check_type(&path, slot, &value)?;
                *slot = coerce(slot, value);
            }
        }
    }
    Ok(())
}

/// `[[regions]]` as given (it replaces any before): an array of tables, each with `part` (a
/// string) and keys of `[material]` (numbers; integers become floats), checked here so that an
/// error names the entry, `regions[1].densty`.
fn regions(base: &Table, value: Value) -> Result<Value, Error> {
    let form = "an array of tables ([[regions]]), each with part = \"…\" and keys of [material]";
    let Value::Array(items) = value else {
        return Err(invalid("regions", &value.to_string(), form));
    };
    let mut allowed = base
        .get("material")
        .and_then(Value::as_table)
        .cloned()
        .unwrap_or_default();
    allowed.insert("part".into(), Value::String(String::new()));
    let mut checked = Vec::with_capacity(items.len());
    for (i, item) in items.into_iter().enumerate() {
        let entry = format!("regions[{i}]");
        let Value::Table(table) = item else {
            return Err(invalid(&entry, &item.to_string(), form));
        };
        if !table.contains_key("part") {
            return Err(Error::MissingKey {
                key: format!("{entry}.part"),
            });
        }
        let mut out = Table::new();
        for (key, value) in table {
            let path = format!("{entry}.{key}");
            let Some(slot) = allowed.get(&key) else {
                return Err(unknown_key(&allowed, &key, path));
            };
            check_type(&path, slot, &value)?;
            out.insert(key, coerce(slot, value));
        }
        checked.push(Value::Table(out));
    }
    Ok(Value::Array(checked))
}

/// A user table that sets `mesh.file` replaces the generator: the base's geometry, cell counts
/// and tractions (on the generator's parts) go, and the user may not give the first two beside
/// the file.
fn take_mesh_file(base: &mut Table, user: &Table) -> Result<(), Error> {
    let Some(Value::Table(mesh)) = user.get("mesh") else {
        return Ok(());
    };
    if !mesh.contains_key("file") {
        return Ok(());
    }
    if let Some(key) = ["nx", "ny", "nz"].into_iter().find(|k| mesh.contains_key(*k)) {
        return Err(invalid(
            &format!("mesh.{key}"),
            &mesh[key].to_string(),
            "no cell counts beside mesh.file (they belong to the structured generator)",
        ));
    }
    if let Some(geometry) = user.get("geometry") {
        return Err(invalid(
            "geometry",
            &geometry.to_string(),
            "no geometry beside mesh.file (the mesh file gives the geometry)",
        ));
    }
    drop_generator(base);
    Ok(())
}

/// A mesh given in memory ([`Scenario::load_with_mesh`]) replaces `mesh.file` and the
/// generator, so the user's scenario may not set them: refused here, by key, because the
/// generator's keys are gone from the base table and the overlay would only say "unknown".
fn refuse_mesh_keys(user: &Table) -> Result<(), Error> {
    let expected = "no mesh keys beside a mesh given in memory (it replaces mesh.file and the generator)";
    if let Some(geometry) = user.get("geometry") {
        return Err(invalid("geometry", &geometry.to_string(), expected));
    }
    if let Some(Value::Table(mesh)) = user.get("mesh") {
        if let Some((key, value)) = mesh.iter().next() {
            return Err(invalid(&format!("mesh.{key}"), &value.to_string(), expected));
        }
    }
    Ok(())
}

/// Removes the structured generator from `base` for a mesh from elsewhere (a file, or given in
/// memory): its geometry and cell counts, and the tractions on the rectangle's parts.
fn drop_generator(base: &mut Table) {
    base.remove("geometry");
    base.insert("mesh".into(), Value::Table(Table::new()));
    // The default's tractions act on the rectangle's parts: another mesh has its own.
    if let Some(Value::Table(loads)) = base.get_mut("loads") {
        loads.insert("traction".into(), Value::Array(Vec::new()));
    }
}

fn type_name(v: &Value) -> &'static str {
    match v {
        Value::String(_) => "a string",
        Value::Integer(_) => "an integer",
        Value::Float(_) => "a number",
        Value::Boolean(_) => "true or false",
        Value::Datetime(_) => "a date",
        Value::Array(_) => "an array",
        Value::Table(_) => "a table",
    }
}

fn check_type(path: &str, base: &Value, user: &Value) -> Result<(), Error> {
    let compatible = matches!(
        (base, user),
        (Value::Float(_), Value::Integer(_))
            | (Value::String(_), Value::String(_))
            | (Value::Integer(_), Value::Integer(_))
            | (Value::Float(_), Value::Float(_))
            | (Value::Boolean(_), Value::Boolean(_))
            | (Value::Array(_), Value::Array(_))
            | (Value::Table(_), Value::Table(_))
    );
    if compatible {
        Ok(())
    } else {
        Err(Error::InvalidValue {
            key: path.to_string(),
            value: user.to_string(),
            expected: type_name(base).to_string(),
        })
    }
}

/// Integers written where the default holds a float become floats (`final_time = 1`).
fn coerce(base: &Value, user: Value) -> Value {
    match (base, user) {
        (Value::Float(_), Value::Integer(i)) => Value::Float(i as f64),
        (Value::Array(b), Value::Array(u)) if b.first().is_some_and(|v| v.is_float()) => {
            Value::Array(u.into_iter().map(|v| coerce(&Value::Float(0.0), v)).collect())
        }
        (_, user) => user,
    }
}

/// Reads `a.b.c=value` as the nested table {a = {b = {c = value}}}; the value is read as TOML,
/// or as a plain string if it is not TOML.
fn parse_override(assignment: &str) -> Result<Table, Error> {
    let Some((path, raw)) = assignment.split_once('=') else {
        return Err(Error::InvalidValue {
            key: assignment.to_string(),
            value: String::new(),
            expected: "an override of the form key.path=value".into(),
        });
    };
    let (path, raw) = (path.trim(), raw.trim());
    let value = match format!("v = {raw}").parse::<Table>() {
        Ok(mut t) => t.remove("v").expect("the key just written"),
        Err(_) => Value::String(raw.to_string()),
    };
    let (parents, last) = match path.rsplit_once('.') {
        Some((parents, last)) => (parents.split('.').collect(), last),
        None => (Vec::new(), path),
    };
    let mut table = Table::from_iter([(last.to_string(), value)]);
    for key in parents.into_iter().rev() {
        table = Table::from_iter([(key.to_string(), Value::Table(table))]);
    }
    Ok(table)
}

/// How two overrides meet on one key (a dotted path).
enum Overlap {
    /// Both set the same key to a value: the later replaces the earlier.
    Same(String),
    /// One sets a key to a value, the other sets keys inside it (`friction=1`, then
    /// `friction.bound=2`).
    Nested(String),
}

/// Where the override tables `a` and `b` meet, if they do (the first such key).
fn overlap(a: &Table, b: &Table, prefix: &str) -> Option<Overlap> {
    for (key, later) in b {
        let Some(earlier) = a.get(key) else { continue };
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        let found = match (earlier, later) {
            (Value::Table(e), Value::Table(l)) => overlap(e, l, &path),
            (Value::Table(_), _) | (_, Value::Table(_)) => Some(Overlap::Nested(path)),
            _ => Some(Overlap::Same(path)),
        };
        if found.is_some() {
            return found;
        }
    }
    None
}

/// Lays the override table `later` into `earlier`: tables merge key by key, anything else is
/// replaced (the later override wins).
fn merge(earlier: &mut Table, later: Table) {
    for (key, value) in later {
        match (earlier.get_mut(&key), value) {
            (Some(Value::Table(e)), Value::Table(l)) => merge(e, l),
            (_, value) => {
                earlier.insert(key, value);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::FrictionSpec;
    use crate::step::SolverKind;

    #[test]
    fn overrides_and_files_overlay_the_default() {
        let s = Scenario::load(Some("[mesh]\nnx = 8\n[time]\nfinal_time = 2"), &["mesh.ny=2".into()]).unwrap();
        assert_eq!((s.mesh.nx, s.mesh.ny), (Some(8), Some(2)));
        assert_eq!(s.time.final_time, 2.0);
        let number =
            |v: f64| crate::scenario::DatumSpec::Scalar(Box::new(crate::scenario::DatumSpec::Numbers(vec![v])));
        let one = crate::scenario::FrictionSpecs::One;
        let t = Scenario::load(None, &["friction={law=\"tresca\", bound=3.0}".into()]).unwrap();
        let tresca = |bound| FrictionSpec::Tresca {
            part: None,
            bound: Some(bound),
            normal: None,
        };
        assert_eq!(t.friction, one(tresca(number(3.0))));
        let t = Scenario::load(None, &["friction.law=tresca".into(), "friction.bound=100".into()]).unwrap();
        assert_eq!(t.friction, one(tresca(number(100.0))));
        assert!(t.warnings.is_empty());
        let back = Scenario::load(
            None,
            &[
                "friction.law=tresca".into(),
                "friction.bound=100".into(),
                "friction={law=\"slip-weakening\", bound=150.0, a=1.0, b=0.2, alpha=100.0}".into(),
                "friction.alpha=50".into(),
            ],
        )
        .unwrap();
        // The deprecated name is read as the new one, with a warning.
        assert_eq!(
            back.friction,
            one(FrictionSpec::VelocityWeakening {
                part: None,
                bound: Some(number(150.0)),
                normal: None,
                a: 1.0,
                b: 0.2,
                alpha: 50.0
            })
        );
        assert!(back.warnings[0].contains("velocity-weakening"), "{:?}", back.warnings);
        let p = Scenario::load(None, &["solver.kind=paper".into()]).unwrap();
        assert_eq!(p.solver.kind, SolverKind::Paper);
    }
}
