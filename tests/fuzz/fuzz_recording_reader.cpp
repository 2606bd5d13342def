// fuzz_recording_reader.cpp — libFuzzer target: recording::RecordingReader
// (host_sim/recording/recording_reader.hpp) on any file content, as `scopekin run` and
// `scopekin discrepancy` read recordings someone else wrote.
//
// Oracles (__builtin_trap() on violation, on top of ASan/UBSan):
//   * a refusal is a RecordingError (no other exception) whose message starts with "fuzz.csv: "
//     and is short whatever the input (at most 1,000 characters: cells are quoted with at most
//     ~80 characters, a missing-column message lists at most the schema's 37 names), naming a
//     line of the file (or 0);
//   * accepted: one line, one extra-cell list per row; lines increasing; times >= 0, strictly
//     increasing, at most max_gap_s apart; every row passes check_row_values; the gaps are
//     find_gaps' of the rows;
//   * every accepted row can be written: RecordingWriter takes the rows (with their extra
//     columns), and reading the written file gives the same rows at wire resolution
//     (quantize_to_wire), the same extra cells and the same gaps; writing those rows again gives
//     the same text (the writer's output is a fixed point).
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <sstream>
#include <string>

#include "fuzz_support.hpp"
#include "host_sim/recording/recording_format.hpp"
#include "host_sim/recording/recording_reader.hpp"
#include "host_sim/recording/wire_values.hpp"

namespace {

using namespace scopekin::recording;

std::string write_rows(const Recording& recording) {
    std::ostringstream out;
    RecordingWriter writer(out, recording.extra_columns);
    for (std::size_t i = 0; i < recording.rows.size(); ++i) {
        writer.write(recording.rows[i], recording.extra_cells[i]);
    }
    return out.str();
}

Recording read_text(const RecordingReader& reader, const std::string& text) {
    std::istringstream in(text);
    return reader.read(in, "fuzz.csv");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    const RecordingReader reader{};
    Recording recording;
    try {
        recording = read_text(reader, text);
    } catch (const RecordingError& error) {
        const std::string message = error.what();
        require(message.rfind("fuzz.csv: ", 0) == 0);
        require(message.size() <= 1000U);
        std::size_t lines = 1;
        for (const char c : text)
            lines += c == '\n' ? 1U : 0U;
        require(error.line() <= lines);
        return 0;
    } catch (...) {
        require(false);  // only RecordingError may leave the reader
    }

    const std::size_t rows = recording.rows.size();
    require(recording.row_lines.size() == rows && recording.extra_cells.size() == rows);
    for (std::size_t i = 0; i < rows; ++i) {
        const RecordingRow& row = recording.rows[i];
        require(row.time_us >= 0);
        require(!check_row_values(row).has_value());
        require(recording.extra_cells[i].size() == recording.extra_columns.size());
        if (i > 0) {
            require(recording.row_lines[i] > recording.row_lines[i - 1]);
            require(row.time_us > recording.rows[i - 1].time_us);
            require(static_cast<double>(row.time_us - recording.rows[i - 1].time_us) <=
                    kDefaultMaxGap_s * 1e6);
        }
    }
    require(recording.gaps == find_gaps(recording.rows, RecordingReaderOptions{}.gap_threshold_s));

    std::string written;
    try {
        written = write_rows(recording);
    } catch (...) {
        require(false);  // a row the reader accepts, the writer writes
    }
    Recording again;
    try {
        again = read_text(reader, written);
    } catch (...) {
        require(false);  // what the writer writes, the reader reads
    }
    require(again.rows.size() == rows);
    require(again.extra_columns == recording.extra_columns);
    require(again.extra_cells == recording.extra_cells);
    for (std::size_t i = 0; i < rows; ++i) {
        require(wire::quantize_to_wire(again.rows[i]) == wire::quantize_to_wire(recording.rows[i]));
    }
    require(again.gaps == recording.gaps);
    require(write_rows(again) == written);
    return 0;
}
