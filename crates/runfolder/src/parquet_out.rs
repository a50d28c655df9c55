//! What the run folder's Parquet writers share: a Snappy-compressed file of
//! a schema, and a row group written from columns held in memory.

use parquet::basic::Compression;
use parquet::data_type::{ByteArray, ByteArrayType, DoubleType, Int64Type};
use parquet::errors::ParquetError;
use parquet::file::properties::WriterProperties;
use parquet::file::writer::SerializedFileWriter;
use parquet::schema::parser::parse_message_type;
use std::fs::File;
use std::sync::Arc;

/// One column's values of a row group, in the schema's order.
pub(crate) enum Column<'a> {
    /// An INT64 column.
    Int64(&'a [i64]),
    /// A DOUBLE column.
    Double(&'a [f64]),
    /// A BYTE_ARRAY (UTF8) column.
    Bytes(&'a [ByteArray]),
}

/// A writer of `schema` (Parquet's message syntax) into `file`.
pub(crate) fn writer(file: File, schema: &str) -> Result<SerializedFileWriter<File>, ParquetError> {
    let schema = Arc::new(parse_message_type(schema)?);
    let props = WriterProperties::builder()
        .set_compression(Compression::SNAPPY)
        .set_created_by("mrsim".into())
        .build();
    SerializedFileWriter::new(file, schema, Arc::new(props))
}

/// Writes `columns` as one row group: one entry per column of the schema,
/// in its order, of its type.
pub(crate) fn write_group(
    writer: &mut SerializedFileWriter<File>,
    columns: &[Column<'_>],
) -> Result<(), ParquetError> {
    let mut group = writer.next_row_group()?;
    let mut values = columns.iter();
    while let Some(mut column) = group.next_column()? {
        let Some(v) = values.next() else {
            return Err(ParquetError::General(
                "more columns in the schema than written".into(),
            ));
        };
        match v {
            Column::Int64(v) => column.typed::<Int64Type>().write_batch(v, None, None),
            Column::Double(v) => column.typed::<DoubleType>().write_batch(v, None, None),
            Column::Bytes(v) => column.typed::<ByteArrayType>().write_batch(v, None, None),
        }?;
        column.close()?;
    }
    if values.next().is_some() {
        return Err(ParquetError::General(
            "more columns written than the schema has".into(),
        ));
    }
    group.close()?;
    Ok(())
}
