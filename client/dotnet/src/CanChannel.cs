// ICanChannel with its receive and transmit FIFOs (section 4.2.3): ICanMessageReader and
// ICanMessageWriter.
using System;
using System.Threading;

namespace Ixxat.Vci3.Bal.Can
{
  public interface ICanMessageReader : IDisposable
  {
    ushort Capacity { get; }
    // The event is signalled when the FIFO holds at least Threshold messages.
    ushort Threshold { get; set; }
    void AssignEvent(AutoResetEvent e);
    void AssignEvent(ManualResetEvent e);
    void AssignEvent(WaitHandle e);
    bool ReadMessage(out CanMessage message);
    int ReadMessages(CanMessage[] messages);
    // The names of section 3.1.1.
    bool GetMessage(out CanMessage message);
    int GetMessages(CanMessage[] messages);
  }

  public interface ICanMessageWriter : IDisposable
  {
    ushort Capacity { get; }
    // The event is signalled when more than Threshold entries are free.
    ushort Threshold { get; set; }
    void AssignEvent(AutoResetEvent e);
    void AssignEvent(ManualResetEvent e);
    void AssignEvent(WaitHandle e);
    bool SendMessage(CanMessage message);
    int SendMessages(CanMessage[] messages);
    // The names of section 3.1.2.
    bool WriteMessage(CanMessage message);
    int WriteMessages(CanMessage[] messages);
  }

  public interface ICanChannel : ICanSocket
  {
    void Initialize(ushort receiveFifoSize, ushort transmitFifoSize, bool exclusive);
    void Activate();
    void Deactivate();
    ICanMessageReader GetMessageReader();
    ICanMessageWriter GetMessageWriter();
    CanChannelStatus ChannelStatus { get; }
  }

  internal sealed class CanChannel : CanSocket, ICanChannel
  {
    IntPtr handle;
    ushort rxSize, txSize, rxThreshold = 1, txThreshold = 1;
    bool initialized, active;
    internal Reader reader;
    internal Writer writer;

    internal CanChannel(BalObject bal, byte port) : base(bal, port)
    {
      Native.Check(Native.canChannelOpen(device, port, 0, out handle),
                   "IBalObject.OpenSocket(" + port + ", ICanChannel)");
    }

    protected override string Kind { get { return "ICanChannel"; } }
    protected override bool OwnCaps(byte[] caps) { return Native.canChannelGetCaps(handle, caps) == Native.VCI_OK; }
    protected override bool OwnLineStatus(byte[] s) { return Native.canChannelGetStatus(handle, s) == Native.VCI_OK; }

    internal IntPtr Handle { get { Alive(); return handle; } }

    public void Initialize(ushort receiveFifoSize, ushort transmitFifoSize, bool exclusive)
    {
      Alive();
      if (active) throw new VciException(Native.E_INVALID_STATE, "ICanChannel.Initialize: the channel is active; Deactivate it first");
      if (receiveFifoSize == 0 || transmitFifoSize == 0)
        throw new VciException(Native.E_INVALIDARG, string.Format(
            "ICanChannel.Initialize: FIFO sizes are counted in messages and must be at least 1 (receive {0}, transmit {1})",
            receiveFifoSize, transmitFifoSize));
      if (exclusive)
      {
        // The channel opened by OpenSocket counts as one: reopened as the exclusive one.
        Native.canChannelClose(handle);
        handle = IntPtr.Zero;
        IntPtr h;
        uint hr = Native.canChannelOpen(device, port, 1, out h);
        if (hr != Native.VCI_OK)
        {
          Native.canChannelOpen(device, port, 0, out handle);
          initialized = false;
          throw new VciException(hr, "ICanChannel.Initialize(exclusive: true): another channel of CAN port " + port +
                                     " is open (in this or another program); an exclusive channel must be the only one: " + Native.Text(hr));
        }
        handle = h;
      }
      rxSize = receiveFifoSize;
      txSize = transmitFifoSize;
      Setup("ICanChannel.Initialize");
      initialized = true;
    }

    void Setup(string what)
    {
      ushort txTh = (ushort)Math.Min(txThreshold + 1, (int)txSize);
      Native.Check(Native.canChannelInitialize(handle, rxSize, Math.Min(rxThreshold, rxSize), txSize, txTh, 0,
                                               0x02 /* CAN_FILTER_PASS */), what);
    }

    internal void SetThreshold(bool rx, ushort value, string what)
    {
      Alive();
      if (rx) { if (value == 0 || value > rxSize) throw new VciException(Native.E_INVALIDARG, what + ": " + value + " is not 1.." + rxSize + " (the FIFO's capacity)"); }
      else if (value >= txSize) throw new VciException(Native.E_INVALIDARG, what + ": " + value + " is not 0.." + (txSize - 1) + " (below the FIFO's capacity)");
      if (active)
        throw new VciException(Native.E_INVALID_STATE, what + ": the threshold can change only while the channel is deactivated (Deactivate, set it, Activate)");
      if (rx) rxThreshold = value; else txThreshold = value;
      Setup(what);
    }

    internal ushort RxThreshold { get { return rxThreshold; } }
    internal ushort TxThreshold { get { return txThreshold; } }
    internal ushort RxSize { get { return rxSize; } }
    internal ushort TxSize { get { return txSize; } }

    void NeedInit(string what)
    {
      Alive();
      if (!initialized)
        throw new VciException(Native.E_INVALID_STATE, what + ": the channel has no FIFOs yet; call ICanChannel.Initialize first");
    }

    public void Activate()
    {
      NeedInit("ICanChannel.Activate");
      Native.Check(Native.canChannelActivate(handle, 1), "ICanChannel.Activate");
      active = true;
    }

    public void Deactivate()
    {
      NeedInit("ICanChannel.Deactivate");
      Native.Check(Native.canChannelActivate(handle, 0), "ICanChannel.Deactivate");
      active = false;
    }

    public ICanMessageReader GetMessageReader()
    {
      NeedInit("ICanChannel.GetMessageReader");
      if (reader != null)
        throw new VciException(Native.E_ACCESSDENIED, "ICanChannel.GetMessageReader: the receive FIFO's reader was obtained already; Dispose it before asking again");
      return reader = new Reader(this);
    }

    public ICanMessageWriter GetMessageWriter()
    {
      NeedInit("ICanChannel.GetMessageWriter");
      if (writer != null)
        throw new VciException(Native.E_ACCESSDENIED, "ICanChannel.GetMessageWriter: the transmit FIFO's writer was obtained already; Dispose it before asking again");
      return writer = new Writer(this);
    }

    public CanChannelStatus ChannelStatus
    {
      get
      {
        Alive();
        var b = new byte[Native.CanChanStatus2Size];
        Native.Check(Native.canChannelGetStatus(handle, b), "ICanChannel.ChannelStatus");
        var s = new CanChannelStatus();
        s.line = ParseLine(b, 0);
        s.activated = b[40] != 0;
        s.overrun = b[41] != 0;
        s.rxLoad = b[42];
        s.txLoad = b[43];
        return s;
      }
    }

    protected override void Release()
    {
      if (reader != null) reader.Dispose();
      if (writer != null) writer.Dispose();
      if (handle != IntPtr.Zero) { Native.canChannelClose(handle); handle = IntPtr.Zero; }
    }

    internal sealed class Reader : ICanMessageReader
    {
      readonly CanChannel channel;
      readonly FifoEvent ev;
      bool disposed;

      internal Reader(CanChannel c)
      {
        channel = c;
        ev = new FifoEvent(ms => Native.canChannelWaitRxEvent(c.handle, ms));
      }

      IntPtr H { get { if (disposed) throw VciException.Disposed("ICanMessageReader"); return channel.Handle; } }
      public ushort Capacity { get { var h = H; return channel.rxSize; } }
      public ushort Threshold
      {
        get { var h = H; return channel.rxThreshold; }
        set { var h = H; channel.SetThreshold(true, value, "ICanMessageReader.Threshold"); }
      }
      public void AssignEvent(AutoResetEvent e) { AssignEvent((WaitHandle)e); }
      public void AssignEvent(ManualResetEvent e) { AssignEvent((WaitHandle)e); }
      public void AssignEvent(WaitHandle e) { var h = H; ev.Assign(FifoEvent.Check(e, "ICanMessageReader")); }

      public bool ReadMessage(out CanMessage message)
      {
        var b = new byte[Native.CanMsg2Size];
        uint hr = Native.canChannelPeekMessage(H, b);
        message = new CanMessage();
        if (hr == Native.E_RXQUEUE_EMPTY) return false;
        Native.Check(hr, "ICanMessageReader.ReadMessage");
        message = CanMessage.FromNative(b);
        ev.Touched();
        return true;
      }

      public int ReadMessages(CanMessage[] messages)
      {
        if (messages == null) throw new VciException(Native.E_INVALIDARG, "ICanMessageReader.ReadMessages: the array is null");
        int n = 0;
        CanMessage m;
        while (n < messages.Length && ReadMessage(out m)) messages[n++] = m;
        return n;
      }

      public bool GetMessage(out CanMessage message) { return ReadMessage(out message); }
      public int GetMessages(CanMessage[] messages) { return ReadMessages(messages); }

      public void Dispose()
      {
        if (disposed) return;
        disposed = true;
        ev.Dispose();
        channel.reader = null;
      }
    }

    internal sealed class Writer : ICanMessageWriter
    {
      readonly CanChannel channel;
      readonly FifoEvent ev;
      bool disposed;

      internal Writer(CanChannel c)
      {
        channel = c;
        ev = new FifoEvent(ms => Native.canChannelWaitTxEvent(c.handle, ms));
      }

      IntPtr H { get { if (disposed) throw VciException.Disposed("ICanMessageWriter"); return channel.Handle; } }
      public ushort Capacity { get { var h = H; return channel.txSize; } }
      public ushort Threshold
      {
        get { var h = H; return channel.txThreshold; }
        set { var h = H; channel.SetThreshold(false, value, "ICanMessageWriter.Threshold"); }
      }
      public void AssignEvent(AutoResetEvent e) { AssignEvent((WaitHandle)e); }
      public void AssignEvent(ManualResetEvent e) { AssignEvent((WaitHandle)e); }
      public void AssignEvent(WaitHandle e) { var h = H; ev.Assign(FifoEvent.Check(e, "ICanMessageWriter")); }

      public bool SendMessage(CanMessage message)
      {
        var h = H;
        if (message.FrameType != CanMsgFrameType.Data) return true;  // discarded unseen (4.2.3.2)
        uint hr = Native.canChannelPostMessage(h, message.ToNative());
        if (hr == Native.E_TXQUEUE_FULL) return false;
        Native.Check(hr, "ICanMessageWriter.SendMessage(" + message + ")");
        ev.Touched();
        return true;
      }

      public int SendMessages(CanMessage[] messages)
      {
        if (messages == null) throw new VciException(Native.E_INVALIDARG, "ICanMessageWriter.SendMessages: the array is null");
        int n = 0;
        while (n < messages.Length && SendMessage(messages[n])) n++;
        return n;
      }

      public bool WriteMessage(CanMessage message) { return SendMessage(message); }
      public int WriteMessages(CanMessage[] messages) { return SendMessages(messages); }

      public void Dispose()
      {
        if (disposed) return;
        disposed = true;
        ev.Dispose();
        channel.writer = null;
      }
    }
  }
}
