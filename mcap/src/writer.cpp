// SPDX-License-Identifier: Apache-2.0
#include "sim/mcap/writer.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <map>
#include <optional>
#include <stdexcept>
#include <vector>

#include "bytes.hpp"
#include "codec.hpp"

namespace sim::mcap {

namespace {

struct ChunkIndex {
  std::uint64_t start_time = 0;
  std::uint64_t end_time = 0;
  std::uint64_t chunk_offset = 0;
  std::uint64_t chunk_length = 0;
  std::map<std::uint16_t, std::uint64_t> message_index_offsets;
  std::uint64_t message_index_length = 0;
  std::uint64_t compressed_size = 0;
  std::uint64_t uncompressed_size = 0;
};

// (log_time, offset of the Message record inside the chunk's records)
using IndexEntries = std::vector<std::pair<std::uint64_t, std::uint64_t>>;

}  // namespace

struct Writer::Impl {
  std::string path;
  WriterOptions options;
  int fd = -1;
  std::optional<Error> failure;  // the first write error; the writer stops there
  bool closed = false;

  std::uint64_t offset = 0;  // bytes in the file, once everything emitted is written
  std::uint64_t written = 0;  // bytes write(2) took
  std::uint32_t crc = 0;     // running CRC of the section being written (data, then summary)
  std::vector<std::byte> out;  // small records waiting for one write(2)

  std::vector<Schema> schemas;
  std::vector<Channel> channels;
  Statistics stats;

  std::vector<std::byte> chunk;  // the open chunk's uncompressed records
  std::vector<std::byte> compressed;
  std::map<std::uint16_t, IndexEntries> chunk_entries;
  std::map<std::uint16_t, std::uint64_t> chunk_message_bytes;  // per channel, in the open chunk
  std::map<std::uint16_t, StoredMessages> stored;              // per channel, in written chunks
  std::uint64_t chunk_start_time = 0;
  std::uint64_t chunk_end_time = 0;
  std::vector<ChunkIndex> chunk_indexes;

  ~Impl() {
    if (fd >= 0) ::close(fd);
  }

  void fail_with_errno(const char* what) {
    if (!failure) {
      failure = Error{ErrorCode::system_error, "cannot " + std::string(what) + " " + path + ": " +
                                                   std::strerror(errno) +
                                                   "; check the disk space and permissions"};
    }
  }

  void write_fully(std::span<const std::byte> data) {
    while (!data.empty() && !failure) {
      const ssize_t n = ::write(fd, data.data(), data.size());
      if (n < 0) {
        if (errno == EINTR) continue;
        fail_with_errno("write");
        return;
      }
      data = data.subspan(static_cast<std::size_t>(n));
      written += static_cast<std::uint64_t>(n);
    }
  }
  void flush_out() {
    write_fully(out);
    out.clear();
  }
  // Every byte of the file goes through here, so offsets and CRCs stay right. `data_crc`: the
  // CRC of `data` when the caller has it already (an uncompressed chunk), so it is not read twice.
  void emit(std::span<const std::byte> data, std::optional<std::uint32_t> data_crc = std::nullopt) {
    if (options.crc) {
      crc = data_crc ? detail::crc32_combine(crc, *data_crc, data.size()) : detail::crc32(data, crc);
    }
    offset += data.size();
    if (data.size() >= (1u << 16)) {
      flush_out();
      write_fully(data);
      return;
    }
    out.insert(out.end(), data.begin(), data.end());
    if (out.size() >= (1u << 20)) flush_out();
  }
  // Emits a record built in `scratch` (a whole record, opcode first).
  void emit_record(const std::vector<std::byte>& scratch) { emit(scratch); }

  void write_header() {
    emit(std::as_bytes(std::span(kMagic)));
    std::vector<std::byte> r;
    detail::ByteWriter w(r);
    const auto at = w.open_record(Opcode::header);
    w.string(options.profile);
    w.string(options.library);
    w.close_record(at);
    emit_record(r);
  }

  static void put_schema(detail::ByteWriter& w, const Schema& s) {
    const auto at = w.open_record(Opcode::schema);
    w.put(s.id);
    w.string(s.name);
    w.string(s.encoding);
    w.string(s.data);  // data is u32-length-prefixed bytes, like a string
    w.close_record(at);
  }
  static void put_channel(detail::ByteWriter& w, const Channel& c) {
    const auto at = w.open_record(Opcode::channel);
    w.put(c.id);
    w.put(c.schema_id);
    w.string(c.topic);
    w.string(c.message_encoding);
    const auto map = w.open_u32_block();
    for (const auto& [key, value] : c.metadata) {
      w.string(key);
      w.string(value);
    }
    w.close_u32_block(map);
    w.close_record(at);
  }

  void flush_chunk() {
    if (chunk.empty() || failure) return;
    const std::uint32_t chunk_crc = options.crc ? detail::crc32(chunk) : 0;
    std::span<const std::byte> body = chunk;
    if (options.compression != Compression::none) {
      try {
        const std::size_t size = detail::compress(options.compression, chunk, compressed, options.zstd_level);
        body = std::span<const std::byte>(compressed).first(size);
      } catch (const std::exception& e) {
        failure = Error{ErrorCode::system_error,
                        std::string("cannot compress a chunk (") + e.what() + "); try --compression none"};
        return;
      }
    }
    ChunkIndex index;
    index.start_time = chunk_start_time;
    index.end_time = chunk_end_time;
    index.chunk_offset = offset;
    index.compressed_size = body.size();
    index.uncompressed_size = chunk.size();

    std::vector<std::byte> prefix;
    detail::ByteWriter w(prefix);
    const std::string_view compression = to_string(options.compression);
    const std::uint64_t content = 8 + 8 + 8 + 4 + 4 + compression.size() + 8 + body.size();
    w.put(static_cast<std::uint8_t>(Opcode::chunk));
    w.put(content);
    w.put(chunk_start_time);
    w.put(chunk_end_time);
    w.put(static_cast<std::uint64_t>(chunk.size()));
    w.put(chunk_crc);
    w.string(compression);
    w.put(static_cast<std::uint64_t>(body.size()));
    emit(prefix);
    // Uncompressed, the body is the chunk whose CRC was just computed.
    emit(body, options.crc && options.compression == Compression::none
                   ? std::optional<std::uint32_t>(chunk_crc)
                   : std::nullopt);
    index.chunk_length = offset - index.chunk_offset;

    const std::uint64_t indexes_start = offset;
    std::vector<std::byte> r;
    for (const auto& [channel_id, entries] : chunk_entries) {
      r.clear();
      detail::ByteWriter iw(r);
      const auto at = iw.open_record(Opcode::message_index);
      iw.put(channel_id);
      const auto array = iw.open_u32_block();
      for (const auto& [time, record_offset] : entries) {
        iw.put(time);
        iw.put(record_offset);
      }
      iw.close_u32_block(array);
      iw.close_record(at);
      index.message_index_offsets[channel_id] = offset;
      emit_record(r);
    }
    index.message_index_length = offset - indexes_start;
    chunk_indexes.push_back(std::move(index));
    ++stats.chunk_count;
    // The chunk is in the file only once written: then its messages count as stored.
    flush_out();
    if (!failure) {
      for (const auto& [channel_id, entries] : chunk_entries) {
        stored[channel_id].messages += entries.size();
        stored[channel_id].bytes += chunk_message_bytes[channel_id];
      }
    }
    chunk.clear();
    chunk_entries.clear();
    chunk_message_bytes.clear();
  }

  static void put_statistics(detail::ByteWriter& w, const Statistics& totals) {
    const auto at = w.open_record(Opcode::statistics);
    w.put(totals.message_count);
    w.put(totals.schema_count);
    w.put(totals.channel_count);
    w.put(totals.attachment_count);
    w.put(totals.metadata_count);
    w.put(totals.chunk_count);
    w.put(totals.message_start_time);
    w.put(totals.message_end_time);
    const auto map = w.open_u32_block();
    for (const auto& [channel_id, count] : totals.channel_message_counts) {
      w.put(channel_id);
      w.put(count);
    }
    w.close_u32_block(map);
    w.close_record(at);
  }
  static void put_chunk_index(detail::ByteWriter& w, const ChunkIndex& c,
                              std::string_view compression) {
    const auto at = w.open_record(Opcode::chunk_index);
    w.put(c.start_time);
    w.put(c.end_time);
    w.put(c.chunk_offset);
    w.put(c.chunk_length);
    const auto map = w.open_u32_block();
    for (const auto& [channel_id, index_offset] : c.message_index_offsets) {
      w.put(channel_id);
      w.put(index_offset);
    }
    w.close_u32_block(map);
    w.put(c.message_index_length);
    w.string(compression);
    w.put(c.compressed_size);
    w.put(c.uncompressed_size);
    w.close_record(at);
  }

  // Where each summary group starts in the file and how long it is (the summary offsets).
  struct SummaryGroup {
    Opcode op;
    std::uint64_t start;
    std::uint64_t length;
  };

  // The data end record, then the summary: schemas and channels (when repeated), statistics and
  // the chunk indexes, each group emitted as one piece so its offset and length are known.
  void write_summary() {
    flush_chunk();
    std::vector<std::byte> r;
    {
      detail::ByteWriter w(r);
      const auto at = w.open_record(Opcode::data_end);
      w.put(options.crc ? crc : std::uint32_t{0});
      w.close_record(at);
    }
    emit_record(r);

    const std::uint64_t summary_start = offset;
    crc = 0;  // the summary CRC covers the summary section alone
    std::vector<SummaryGroup> groups;
    auto group = [&](Opcode op, auto&& write_records) {
      const std::uint64_t start = offset;
      r.clear();
      detail::ByteWriter w(r);
      write_records(w);
      if (r.empty()) return;
      emit_record(r);
      groups.push_back({op, start, offset - start});
    };
    group(Opcode::schema, [&](detail::ByteWriter& w) {
      if (options.repeat_schemas) for (const auto& s : schemas) put_schema(w, s);
    });
    group(Opcode::channel, [&](detail::ByteWriter& w) {
      if (options.repeat_channels) for (const auto& c : channels) put_channel(w, c);
    });
    group(Opcode::statistics, [&](detail::ByteWriter& w) { put_statistics(w, stats); });
    group(Opcode::chunk_index, [&](detail::ByteWriter& w) {
      for (const auto& c : chunk_indexes) put_chunk_index(w, c, to_string(options.compression));
    });
    write_summary_offsets_and_footer(groups, summary_start);
  }

  // The summary offset records, the footer and the closing magic.
  void write_summary_offsets_and_footer(const std::vector<SummaryGroup>& groups,
                                        std::uint64_t summary_start) {
    const std::uint64_t summary_offset_start = offset;
    std::vector<std::byte> r;
    detail::ByteWriter w(r);
    for (const auto& g : groups) {
      const auto at = w.open_record(Opcode::summary_offset);
      w.put(static_cast<std::uint8_t>(g.op));
      w.put(g.start);
      w.put(g.length);
      w.close_record(at);
    }
    emit_record(r);

    r.clear();
    w.put(static_cast<std::uint8_t>(Opcode::footer));
    w.put(std::uint64_t{20});
    w.put(summary_start);
    w.put(summary_offset_start);
    emit_record(r);  // the summary CRC covers the footer up to its own field
    r.clear();
    w.put(options.crc ? crc : std::uint32_t{0});
    w.bytes(std::as_bytes(std::span(kMagic)));
    emit_record(r);
    flush_out();
  }
};

Writer::Writer(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Writer::Writer(Writer&&) noexcept = default;
Writer& Writer::operator=(Writer&& other) noexcept {
  if (this != &other) {
    if (impl_) close();
    impl_ = std::move(other.impl_);
  }
  return *this;
}
Writer::~Writer() {
  if (impl_) close();
}

Expected<Writer> Writer::create(const std::string& path, const WriterOptions& options) {
  auto impl = std::make_unique<Impl>();
  impl->path = path;
  impl->options = options;
  // A FIFO would block the open until someone reads it, and a recording is no stream of bytes.
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && (S_ISFIFO(st.st_mode) || S_ISSOCK(st.st_mode))) {
    return Error{ErrorCode::system_error,
                 path + " is a FIFO or socket, not a file; choose a file path with -o"};
  }
  impl->fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC | O_NONBLOCK, 0644);
  if (impl->fd >= 0) ::fcntl(impl->fd, F_SETFL, ::fcntl(impl->fd, F_GETFL) & ~O_NONBLOCK);
  if (impl->fd < 0) {
    return Error{errno == EACCES ? ErrorCode::permission_denied : ErrorCode::system_error,
                 "cannot create " + path + ": " + std::strerror(errno) +
                     "; choose a writable path with -o"};
  }
  impl->chunk.reserve(static_cast<std::size_t>(options.chunk_size) + (1u << 16));
  impl->write_header();
  if (impl->failure) return *impl->failure;
  return Writer(std::move(impl));
}

std::uint16_t Writer::add_schema(std::string_view name, std::string_view encoding,
                                 std::string_view data) {
  Schema s{static_cast<std::uint16_t>(impl_->schemas.size() + 1), std::string(name),
           std::string(encoding), std::string(data)};
  std::vector<std::byte> r;
  detail::ByteWriter w(r);
  Impl::put_schema(w, s);
  impl_->emit_record(r);
  impl_->schemas.push_back(std::move(s));
  ++impl_->stats.schema_count;
  return impl_->schemas.back().id;
}

std::uint16_t Writer::add_channel(std::uint16_t schema_id, std::string_view topic,
                                  std::string_view message_encoding, const Metadata& metadata) {
  Channel c{static_cast<std::uint16_t>(impl_->channels.size() + 1), schema_id, std::string(topic),
            std::string(message_encoding), metadata};
  std::vector<std::byte> r;
  detail::ByteWriter w(r);
  Impl::put_channel(w, c);
  impl_->emit_record(r);
  impl_->channels.push_back(std::move(c));
  ++impl_->stats.channel_count;
  impl_->stats.channel_message_counts[impl_->channels.back().id] = 0;
  return impl_->channels.back().id;
}

std::optional<Error> Writer::write(const MessageHeader& header, std::span<const std::byte> data) {
  Impl& m = *impl_;
  if (m.failure) return m.failure;
  if (m.closed) return Error{ErrorCode::invalid_argument, "the MCAP writer is already closed"};
  if (m.chunk.empty()) {
    m.chunk_start_time = header.log_time;
    m.chunk_end_time = header.log_time;
  }
  m.chunk_start_time = std::min(m.chunk_start_time, header.log_time);
  m.chunk_end_time = std::max(m.chunk_end_time, header.log_time);
  m.chunk_entries[header.channel_id].emplace_back(header.log_time, m.chunk.size());
  m.chunk_message_bytes[header.channel_id] += data.size();
  detail::ByteWriter w(m.chunk);
  w.put(static_cast<std::uint8_t>(Opcode::message));
  w.put(static_cast<std::uint64_t>(2 + 4 + 8 + 8 + data.size()));
  w.put(header.channel_id);
  w.put(header.sequence);
  w.put(header.log_time);
  w.put(header.publish_time);
  w.bytes(data);

  Statistics& s = m.stats;
  if (s.message_count == 0) {
    s.message_start_time = header.log_time;
    s.message_end_time = header.log_time;
  }
  ++s.message_count;
  ++s.channel_message_counts[header.channel_id];
  s.message_start_time = std::min(s.message_start_time, header.log_time);
  s.message_end_time = std::max(s.message_end_time, header.log_time);
  if (m.chunk.size() >= m.options.chunk_size) m.flush_chunk();
  return m.failure;
}

std::optional<Error> Writer::close() {
  Impl& m = *impl_;
  if (m.closed) return m.failure;
  m.closed = true;
  m.write_summary();
  if (m.fd >= 0 && ::close(m.fd) != 0) m.fail_with_errno("close");
  m.fd = -1;
  return m.failure;
}

const Statistics& Writer::statistics() const noexcept { return impl_->stats; }
std::uint64_t Writer::bytes_written() const noexcept {
  // After a failure, only what write(2) took; else also the records still buffered.
  return impl_->failure ? impl_->written : impl_->offset;
}
StoredMessages Writer::stored(std::uint16_t channel_id) const {
  const auto it = impl_->stored.find(channel_id);
  return it == impl_->stored.end() ? StoredMessages{} : it->second;
}

}  // namespace sim::mcap
